// Camera responses per colour channel, as `hdr4d calibrate` recovers them: its response.csv
// holds a header "code,r,g,b" and one row per 8-bit code with each channel's relative
// exposure x(code). merge-hdr applies each channel's own curve; single-curve users of
// "table:<file>" get the channels' geometric mean (TableCrf::FromCsv).
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/radiometry/crf.h"

namespace hdr4d {

// The x-per-code column of each channel when `path` has calibrate's layout (first header field
// "code"), else nullopt. The code column must count 0..N-1 (N >= 2); x must be finite, >= 0 and
// non-decreasing (equal neighbours, from printing, are separated by a hair). Errors name the
// file and line.
std::optional<std::vector<std::vector<double>>> ReadPerChannelResponse(const std::string& path);

// One curve per channel for "table:<calibrate's response.csv>", else the one curve of ParseCrf.
std::vector<std::unique_ptr<Crf>> ParseChannelCrfs(const std::string& spec);

}  // namespace hdr4d
