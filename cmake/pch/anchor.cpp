// The one source of the targets that only build a precompiled header (hdr4d_lib_pch,
// hdr4d_test_pch in cmake/Hdr4dHelpers.cmake): a CMake target needs a source to compile it with.
