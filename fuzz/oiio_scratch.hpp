// Shared by the fuzz targets that feed OpenImageIO through a file: one scratch file per process
// (in RAM where /dev/shm is writable) and OpenImageIO on one thread.
#pragma once
#include <OpenImageIO/imageio.h>
#include <unistd.h>

#include <string>

inline std::string fuzz_scratch_path(const std::string& tag) {
    const char* shm = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
    return std::string(shm) + "/reprise-fuzz-" + tag + std::to_string(getpid()) + ".exr";
}

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    OIIO::attribute("threads", 1);
    OIIO::attribute("exr_threads", 1);
    return 0;
}
