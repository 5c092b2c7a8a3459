// What `hdr4d dataset check` prints for a checked scene (CheckDataset): every problem, then what
// the scene is (layout, frames per split, cameras, exposures, time span, HDR ground truth,
// resolution, point cloud and the scene profile), as text for people or as JSON for programs.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "core/dataset/dataset.h"

namespace hdr4d {

// {ok, problems: [{file, frame, key, message, text}], summary: {...}, profile: {...}}; summary
// and profile are null when the transforms files could not be read far enough.
nlohmann::json DatasetReportJson(const DatasetReport& report);

// One line per problem (file: frame N: key: message) and their count, then the summary and the
// profile (or why there is none), and "ok: no problems" when there is none.
std::string DatasetReportText(const DatasetReport& report);

}  // namespace hdr4d
