# `cpack` in the build folder: one Debian package, reprise_<version>_<arch>.deb, holding everything
# `cmake --install` installs (libraries, headers, CMake package, reprise.pc, the `reprise` command,
# the Python package in /usr/lib/python3/dist-packages) and the Blender add-on as a zip under
# /usr/share/reprise/blender. scripts/package-check builds it, installs it with apt-get and uses it.
include(GNUInstallDirs)

set(reprise_blender_zip ${PROJECT_BINARY_DIR}/reprise_fruc.zip)
file(GLOB reprise_blender_sources CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/integrations/blender/reprise_fruc/*)
add_custom_command(OUTPUT ${reprise_blender_zip}
  COMMAND ${CMAKE_COMMAND} -E tar cf ${reprise_blender_zip} --format=zip reprise_fruc
  WORKING_DIRECTORY ${PROJECT_SOURCE_DIR}/integrations/blender
  DEPENDS ${reprise_blender_sources}
  COMMENT "Zipping the Blender add-on")
add_custom_target(reprise_blender_addon ALL DEPENDS ${reprise_blender_zip})
install(FILES ${reprise_blender_zip} DESTINATION ${CMAKE_INSTALL_DATADIR}/reprise/blender)

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME reprise)
set(CPACK_PACKAGE_VENDOR reprise)
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "frames nobody rendered, from rendered frames with depth and motion")
set(CPACK_PACKAGE_DESCRIPTION
    "Frame-rate upconversion, the second eye of a stereo pair and a remote-rendering codec and\
 stream, made from rendered colour, depth and motion: the reprise command, C++ libraries with\
 their CMake package, the C interface (reprise.h, libreprise.so), the Python module and the\
 Blender add-on.")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_MAINTAINER "reprise developers <dev@reprise.invalid>")
set(CPACK_DEBIAN_PACKAGE_SECTION graphics)
# Run-time libraries of the command and the Python module come from dpkg-shlibdeps; the rest is
# what the Python package imports and what the static libraries need to link a consumer.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_DEPENDS "python3, python3-numpy")
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS
    "python3-distributed, libopencv-dev, libopencv-contrib-dev, libopenimageio-dev, libglm-dev,\
 libtinygltf-dev, libhwy-dev, libsodium-dev, libegl-dev, libgles-dev, pkg-config")
set(CPACK_DEBIAN_PACKAGE_SUGGESTS blender)
include(CPack)
