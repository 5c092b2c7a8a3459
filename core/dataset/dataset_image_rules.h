// What a dataset's images must be, in one place, so that `hdr4d dataset check` finds exactly
// what training, rendering and LDR synthesis would refuse, in the same words:
//  - a frame's file_path is its LDR image: display-encoded integers (PNG/JPEG), grey, RGB or
//    RGBA (training composites RGBA over the background);
//  - its exr_file_path is HDR ground truth: linear float values (EXR/HDR), at least RGB,
//    finite, never negative, and not all zero (the HDR loss divides by the maximum).
// Each check returns "" or the problem (without the file name: callers add it).
#pragma once

#include <string>

#include "core/image/image.h"
#include "core/image/image_io.h"

namespace hdr4d {

// From the header alone (format and channels): the checks a header can answer.
std::string LdrImageHeaderProblem(const ImageSpecInfo& spec);
std::string HdrImageHeaderProblem(const ImageSpecInfo& spec);

// From the pixels: the header checks, plus the values (NaN/Inf are refused by ReadImage).
std::string LdrImageProblem(const Image& image);
std::string HdrImageProblem(const Image& image);

// Reads an HDR ground-truth image and throws hdr4d::Error "<path>: <problem>" when it breaks a
// rule above: every reader of exr_file_path goes through it.
Image ReadHdrGroundTruth(const std::filesystem::path& path);

}  // namespace hdr4d
