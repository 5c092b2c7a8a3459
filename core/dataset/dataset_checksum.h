// The files a dataset is made of and their SHA-256 (core/files/sha256.h): what the benchmark
// harness hashes into a scene's checksum, and what a training run records
// (RUN/data_checksums.json) so that `train --resume` notices a changed dataset (issue 51 §15).
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "core/dataset/dataset.h"

namespace hdr4d {

// The dataset's JSON files, point3d.ply and every frame's image and EXR (each once, in path
// order) with their SHA-256, "absent" for a file that is not there (an LDR image not made yet).
std::vector<std::pair<std::filesystem::path, std::string>> HashDatasetFiles(const Dataset& dataset);

// What a run records of its data: the frames of each split in order (their file paths) and the
// hash of every file, by its path relative to the dataset's root.
struct DatasetRecord {
  std::vector<std::string> frames;  // "train images/x.png", split by split, in the JSON's order
  std::vector<std::pair<std::string, std::string>> files;  // relative path, SHA-256

  nlohmann::json ToJson() const;
  // Throws hdr4d::Error naming `source` when the JSON is not such a record.
  static DatasetRecord FromJson(const nlohmann::json& json, const std::string& source);
};
DatasetRecord RecordDataset(const Dataset& dataset);

// "" when `now` is `before`, else the first change in words: a frame count, a frame's file
// (order included), then a file whose bytes differ, e.g. "images/a.png changed (its SHA-256
// differs)".
std::string DescribeDatasetChange(const DatasetRecord& before, const DatasetRecord& now);

// What a render reads of a dataset, against `before`: the frames of each split and the JSON files
// the record holds (cameras, times, exposures); "" when they are the same, else the first change
// as above. Images and the point cloud are neither hashed nor compared (a render reads neither).
std::string DescribeCameraChange(const DatasetRecord& before, const Dataset& now);

}  // namespace hdr4d
