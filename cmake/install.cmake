# `cmake --install`: headers, the module libraries, the `reprise` executable, a CMake package
# (find_package(reprise CONFIG) -> reprise::core, ::warp, ::stereo, ::codec, ::net, ::gl, ::gpu,
# ::server, ::client, ::capi) and reprise.pc for pkg-config; with the C interface, reprise.h and
# libreprise.so. Included from the top-level CMakeLists.txt after every module.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(reprise_modules core warp stereo codec net gl gpu server client)
foreach(module ${reprise_modules})
  # Each module's CMakeLists names its public include folder as a build-tree path; installed
  # consumers find the same headers under the install prefix.
  set_target_properties(reprise_${module} PROPERTIES
    EXPORT_NAME ${module}
    INTERFACE_INCLUDE_DIRECTORIES
      "$<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/${module}/include>;$<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>")
  add_library(reprise::${module} ALIAS reprise_${module})
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${module}/include/reprise
          DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endforeach()
list(TRANSFORM reprise_modules PREPEND reprise_ OUTPUT_VARIABLE reprise_module_targets)

install(TARGETS ${reprise_module_targets} EXPORT repriseTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(TARGETS reprise RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
if(TARGET reprise_capi)
  set_target_properties(reprise_capi PROPERTIES EXPORT_NAME capi)
  add_library(reprise::capi ALIAS reprise_capi)
  install(TARGETS reprise_capi EXPORT repriseTargets
          LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
  install(FILES ${PROJECT_SOURCE_DIR}/capi/include/reprise.h DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endif()

set(reprise_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/reprise)
install(EXPORT repriseTargets NAMESPACE reprise:: DESTINATION ${reprise_cmake_dir})
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/repriseConfig.cmake.in
  ${PROJECT_BINARY_DIR}/repriseConfig.cmake INSTALL_DESTINATION ${reprise_cmake_dir})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/repriseConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/repriseConfig.cmake
              ${PROJECT_BINARY_DIR}/repriseConfigVersion.cmake
        DESTINATION ${reprise_cmake_dir})

# The .pc file finds its prefix from where it lies, so `cmake --install --prefix` anywhere works.
file(RELATIVE_PATH reprise_pc_to_prefix /${CMAKE_INSTALL_LIBDIR}/pkgconfig /)
string(REGEX REPLACE "/$" "" reprise_pc_to_prefix "${reprise_pc_to_prefix}")
configure_file(${CMAKE_CURRENT_LIST_DIR}/reprise.pc.in ${PROJECT_BINARY_DIR}/reprise.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/reprise.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
