// The calibration grid's parsing (every key checked), a row read from a finished variant's
// files, and the tables (benchmark/calibration_suite.h). The grid itself renders and runs COLMAP
// (minutes per variant): it is run by hand (BENCHMARKS.md), not here.
#include "benchmark/calibration_suite.h"

#include <gtest/gtest.h>

#include "benchmark/suite.h"
#include "core/files/json_util.h"
#include "tests/testing.h"

namespace hdr4d::bench {
namespace {
namespace fs = std::filesystem;
using testing::ErrorOf;

nlohmann::json MinimalGrid() {
  return nlohmann::json::parse(R"({"name": "g", "variants": [{"name": "a", "datagen": {"size": "320x240"}}]})");
}

std::string GridError(const nlohmann::json& j) {
  return ErrorOf([&] { ParseCalibrationGrid(j, "/x/grid.json"); });
}

bool Has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

TEST(CalibrationSuite, ShippedGridParses) {
  const CalibrationGrid g = LoadCalibrationGrid(SuitesDir() / "calibration.json");
  EXPECT_EQ(g.name, "calibration");
  EXPECT_GE(g.variants.size(), 6u);
  EXPECT_EQ(g.variants.front().name, "small");
  // Issue 54's proof run: seed 7, which no pass tuned on.
  const CalibrationGrid proof = LoadCalibrationGrid(SuitesDir() / "calibration-untuned.json");
  EXPECT_EQ(proof.seeds, std::vector<int>{7});
  EXPECT_GE(proof.variants.size(), 7u);
  // The final proof run: the same variants at seed 11.
  const CalibrationGrid final_run = LoadCalibrationGrid(SuitesDir() / "calibration-final.json");
  EXPECT_EQ(final_run.seeds, std::vector<int>{11});
  EXPECT_EQ(final_run.variants.size(), proof.variants.size());
  // Stop 65's proof run: the same variants at seed 31.
  const CalibrationGrid s31 = LoadCalibrationGrid(SuitesDir() / "calibration-s31.json");
  EXPECT_EQ(s31.seeds, std::vector<int>{31});
  EXPECT_EQ(s31.variants.size(), proof.variants.size());
  // Stop 66's: the same at seed 41, with a low-resolution vignetted rig added.
  const CalibrationGrid s41 = LoadCalibrationGrid(SuitesDir() / "calibration-s41.json");
  EXPECT_EQ(s41.seeds, std::vector<int>{41});
  EXPECT_EQ(s41.variants.size(), proof.variants.size() + 1);
}

TEST(CalibrationSuite, BadGridsNameTheFileAndKey) {
  nlohmann::json j = MinimalGrid();
  j["colour"] = 1;
  EXPECT_TRUE(Has(GridError(j), "/x/grid.json: unknown key 'colour'")) << GridError(j);
  j = MinimalGrid();
  j["variants"][0]["lens"] = "none";
  EXPECT_TRUE(Has(GridError(j), "variants[0]: unknown key 'lens'")) << GridError(j);
  j = MinimalGrid();
  j["variants"][0]["datagen"]["seed"] = 4;  // the grid's seeds axis sets it
  EXPECT_TRUE(Has(GridError(j), "seed")) << GridError(j);
  j = MinimalGrid();
  j["variants"].push_back(j["variants"][0]);
  EXPECT_TRUE(Has(GridError(j), "name 'a' is used twice")) << GridError(j);
  j = MinimalGrid();
  j["variants"][0]["name"] = "a/b";
  EXPECT_TRUE(Has(GridError(j), "no slashes")) << GridError(j);
  j = MinimalGrid();
  j["seeds"] = {-1};
  EXPECT_TRUE(Has(GridError(j), "seeds")) << GridError(j);
  j = MinimalGrid();
  j.erase("variants");
  EXPECT_TRUE(Has(GridError(j), "'variants' must be a non-empty array")) << GridError(j);
}

// A finished variant as calibrate leaves it: the row and the targets it met.
void WriteFinishedVariant(const fs::path& cal, double pairs_deg, double slope) {
  WriteJsonFile(cal / "truth_comparison.json",
                {{"geometry", {{"max_rotation_error_deg", 0.8}, {"max_rotation_error_oriented_deg", 0.3},
                               {"max_relative_rotation_error_deg", pairs_deg}, {"max_position_error_relative", 0.004},
                               {"max_focal_error_relative", 0.006}}},
                 {"hdr", {{"loglog_slope", slope}, {"median_relative_error", 0.02},
                          {"dark_fifth_median_relative_error", 0.03}, {"camera_disagreement", 0.01}}}});
  WriteJsonFile(cal / "calibration.json",
                {{"cameras", {{{"distortion_kept", false}}, {{"distortion_kept", true}, {"distortion_terms", 1}}}},
                 {"camera_agreement", {{"disagreement_after", 0.05}}},
                 {"seconds", {{"geometry", 10.0}, {"radiometry", 2.5}}}});
  WriteJsonFile(cal / "rig.json", {{"model_source", "COLMAP 3.8 (...), rung 2 of the registration ladder (x)"},
                                   {"extra_images_registered", 3}});
}

TEST(CalibrationSuite, ARowFromAFinishedVariant) {
  testing::TempDir dir;
  WriteFinishedVariant(dir.path(), 0.2, 1.01);
  CalibrationRow r = ReadCalibrationRow(dir.path(), {});
  EXPECT_EQ(r.registration, "all cameras, extra 3, rung 2");
  EXPECT_EQ(r.distortion, "- k1");
  EXPECT_DOUBLE_EQ(r.rotation_pairs_deg, 0.2);
  EXPECT_DOUBLE_EQ(r.calibrate_seconds, 12.5);
  EXPECT_TRUE(r.missed.empty());
  r.variant = "v";
  EXPECT_TRUE(Has(CalibrationTableMarkdown({r}), "| v | 0 | all cameras, extra 3, rung 2 | 0.200 / 0.300 / 0.800 | 0.40 | 0.60% | - k1 | 1.010 |"))
      << CalibrationTableMarkdown({r});
  EXPECT_TRUE(Has(CalibrationTableMarkdown({r}), "all met"));
  // The slope against the raw render and a perfect calibration's there, where the comparison has them.
  nlohmann::json truth = ReadJsonFile(dir.path() / "truth_comparison.json");
  truth["hdr"]["loglog_slope_render"] = 0.9;
  truth["hdr"]["loglog_slope_render_floor"] = 0.905;
  WriteJsonFile(dir.path() / "truth_comparison.json", truth);
  r = ReadCalibrationRow(dir.path(), {});
  EXPECT_TRUE(Has(CalibrationTableMarkdown({r}), "| 1.010 (0.900; 0.905) |")) << CalibrationTableMarkdown({r});
  EXPECT_TRUE(r.missed.empty());

  // Vignetting: the falloff divided out against the capture's, camera by camera.
  EXPECT_TRUE(Has(CalibrationTableMarkdown({r}), "| 0 (0), 0.000 |")) << CalibrationTableMarkdown({r});
  truth["cameras"] = {{{"name", "a"}, {"vignetting_truth", 0.2}}, {{"name", "b"}, {"vignetting_truth", 0.0}}};
  WriteJsonFile(dir.path() / "truth_comparison.json", truth);
  nlohmann::json cal = ReadJsonFile(dir.path() / "calibration.json");
  cal["camera_agreement"]["vignetting_applied"] = {0.23, 0.0};
  WriteJsonFile(dir.path() / "calibration.json", cal);
  r = ReadCalibrationRow(dir.path(), {});
  EXPECT_EQ(r.vignetting_corrected, 1);
  EXPECT_EQ(r.vignetting_true, 1);
  EXPECT_NEAR(r.vignetting_error, 0.03, 1e-12);
  EXPECT_TRUE(Has(CalibrationTableMarkdown({r}), "| 1 (1), 0.030 |")) << CalibrationTableMarkdown({r});

  WriteFinishedVariant(dir.path(), 0.4, 0.9);
  r = ReadCalibrationRow(dir.path(), {});
  EXPECT_EQ(r.missed, (std::vector<std::string>{"rotation", "slope"}));
  CalibrationRow failed{.variant = "w", .failed = "datagen: exit code 1"};
  const std::string md = CalibrationTableMarkdown({r, failed});
  EXPECT_TRUE(Has(md, "missed: rotation, slope")) << md;
  EXPECT_TRUE(Has(md, "| w | 0 | failed: datagen: exit code 1 |")) << md;
  EXPECT_TRUE(Has(CalibrationTableCsv({r, failed}), "w,0,\"datagen: exit code 1\"")) << CalibrationTableCsv({failed});
}

TEST(CalibrationSuite, AMissingResultNamesTheFile) {
  testing::TempDir dir;
  EXPECT_TRUE(Has(ErrorOf([&] { ReadCalibrationRow(dir.path(), {}); }), "truth_comparison.json"));
  WriteJsonFile(dir.path() / "truth_comparison.json", {{"geometry", nlohmann::json::object()}});
  WriteJsonFile(dir.path() / "calibration.json", nlohmann::json::object());
  EXPECT_TRUE(Has(ErrorOf([&] { ReadCalibrationRow(dir.path(), {}); }), "with --truth"));
}

TEST(CalibrationSuite, AnUnknownVariantIsRefusedBeforeAnythingRuns) {
  testing::TempDir dir;
  CalibrationSuiteOptions options;
  options.work = dir.path();
  options.only = {"nope"};
  EXPECT_TRUE(Has(ErrorOf([&] { RunCalibrationSuite(ParseCalibrationGrid(MinimalGrid(), "/x/g.json"), options); }),
                  "no variant 'nope'"));
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

}  // namespace
}  // namespace hdr4d::bench
