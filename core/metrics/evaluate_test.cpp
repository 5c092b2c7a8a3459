#include "core/metrics/evaluate.h"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "core/util/error.h"
#include "core/metrics/flip.h"
#include "core/metrics/hdr_alignment.h"
#include "core/image/image_io.h"
#include "core/image/image_resize.h"
#include "core/metrics/metrics.h"
#include "core/util/parallel.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {

using hdr4d::testing::ErrorOf;

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::Not;
using testing::RandomImage;
using testing::RunHdr4d;
using testing::TempDir;

const std::set<std::string> kLdrKeys = {"name", "psnr", "psnr_channel_mean", "ssim", "flip"};
const std::set<std::string> kHdrKeys = {
    "name",           "mu_psnr",           "mu_ssim",         "mu_psnr_gt_max",
    "mu_ssim_gt_max", "pu21_psnr",         "pu21_ssim",       "hdr_flip",        "hdr_flip_aligned", "hdr_align_scale",
    "hdr_log_slope",  "hdr_log_corr",      "hdr_log_contrast", "hdr_measured_fraction", "mu_psnr_aligned",
    "mu_ssim_aligned", "pu21_psnr_aligned", "pu21_ssim_aligned"};

std::set<std::string> KeysOf(const nlohmann::json& object) {
  std::set<std::string> keys;
  for (const auto& [k, v] : object.items()) keys.insert(k);
  return keys;
}

void WriteLdr(const fs::path& path, int w, int h, unsigned seed) {
  WriteImage(path, RandomImage(w, h, 3, seed, 0.0f, 1.0f, Encoding::kSrgb));
}

void WriteHdr(const fs::path& path, int w, int h, unsigned seed, float hi = 4.0f) {
  WriteImage(path, RandomImage(w, h, 3, seed, 0.0f, hi), {.format = PixelFormat::kFloat});
}

// A gt folder with a.png, b.png, an extra image (another split's, skipped) and a non-image file;
// predictions for a and b.
struct LdrFolders {
  TempDir dir;
  fs::path pred = dir / "pred";
  fs::path gt = dir / "gt";
  LdrFolders() {
    WriteLdr(gt / "b.png", 16, 12, 1);
    WriteLdr(gt / "a.png", 16, 12, 2);
    testing::WriteTextFile(gt / "notes.txt", "not an image");
    WriteLdr(pred / "a.png", 16, 12, 3);
    WriteLdr(pred / "b.png", 16, 12, 4);
    WriteLdr(gt / "extra.png", 16, 12, 5);
  }
};

TEST(EvaluateTest, FoldersMatchByNameInSortedOrder) {
  LdrFolders f;
  const nlohmann::json result = EvaluatePaths(f.pred, f.gt);
  EXPECT_EQ(KeysOf(result), (std::set<std::string>{"pairs", "mean", "identical_pairs"}));
  EXPECT_EQ(result["identical_pairs"], 0);
  ASSERT_EQ(result["pairs"].size(), 2u);
  EXPECT_EQ(result["pairs"][0]["name"], "a.png");
  EXPECT_EQ(result["pairs"][1]["name"], "b.png");
  for (const auto& pair : result["pairs"]) EXPECT_EQ(KeysOf(pair), kLdrKeys);

  // The values are LdrMetrics of the images as stored, and mean = mean of the pairs.
  const std::string names[] = {"a.png", "b.png"};
  for (int i = 0; i < 2; ++i) {
    const MetricList m = LdrMetrics(ReadImage(f.pred / names[i]), ReadImage(f.gt / names[i]));
    for (const auto& [key, value] : m)
      EXPECT_DOUBLE_EQ(result["pairs"][i][key].get<double>(), value);
    EXPECT_DOUBLE_EQ(result["pairs"][i]["flip"].get<double>(),
                     Flip(ReadImage(f.pred / names[i]), ReadImage(f.gt / names[i])));
  }
  for (const std::string key : {"psnr", "psnr_channel_mean", "ssim", "flip"}) {
    const double mean =
        (result["pairs"][0][key].get<double>() + result["pairs"][1][key].get<double>()) / 2;
    EXPECT_DOUBLE_EQ(result["mean"][key].get<double>(), mean) << key;
  }
  EXPECT_EQ(KeysOf(result["mean"]),
            (std::set<std::string>{"psnr", "psnr_channel_mean", "ssim", "flip"}));
}

TEST(EvaluateTest, HdrPairsGetHdrKeysOnly) {
  TempDir dir;
  WriteHdr(dir / "gt" / "x.exr", 12, 10, 6);
  WriteHdr(dir / "pred" / "x.exr", 12, 10, 7, 8.0f);
  const nlohmann::json result = EvaluatePaths(dir / "pred", dir / "gt");
  ASSERT_EQ(result["pairs"].size(), 1u);
  EXPECT_EQ(KeysOf(result["pairs"][0]), kHdrKeys);
  const MetricList m =
      HdrMetrics(ReadImage(dir / "pred" / "x.exr"), ReadImage(dir / "gt" / "x.exr"));
  for (const auto& [key, value] : m) {
    EXPECT_DOUBLE_EQ(result["pairs"][0][key].get<double>(), value) << key;
    EXPECT_DOUBLE_EQ(result["mean"][key].get<double>(), value) << key;
  }
}

// With the view's LDR brackets, the aligned metrics use the pixels some bracket measures.
TEST(EvaluateTest, BracketsDecideTheMeasuredPixels) {
  TempDir dir;
  const int w = 12, h = 10;
  WriteHdr(dir / "gt" / "x.exr", w, h, 6);
  WriteHdr(dir / "pred" / "x.exr", w, h, 7, 8.0f);
  // Bracket 0 is clipped on the left half, bracket 1 is black on the left 3 columns.
  Image e0(w, h, 3, Encoding::kSrgb), e1(w, h, 3, Encoding::kSrgb);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      for (int c = 0; c < 3; ++c) {
        e0.at(x, y, c) = x < w / 2 ? 1.0f : 0.4f;
        e1.at(x, y, c) = x < 3 ? 0.0f : 0.6f;
      }
    }
  }
  WriteImage(dir / "x_e0.png", e0);
  WriteImage(dir / "x_e1.png", e1);
  const EvalBrackets brackets = {{"x.exr", {dir / "x_e0.png", dir / "x_e1.png"}}};
  const nlohmann::json with = EvaluatePaths(dir / "pred", dir / "gt", &brackets);
  const nlohmann::json without = EvaluatePaths(dir / "pred", dir / "gt");
  EXPECT_DOUBLE_EQ(with["pairs"][0]["hdr_measured_fraction"].get<double>(), 9.0 / 12.0);
  EXPECT_GT(without["pairs"][0]["hdr_measured_fraction"].get<double>(), 0.99);
  // The reference's protocols do not depend on the mask.
  EXPECT_EQ(with["pairs"][0]["mu_psnr"], without["pairs"][0]["mu_psnr"]);
  const std::vector<std::uint8_t> mask =
      MeasurableInBrackets({ReadImage(dir / "x_e0.png"), ReadImage(dir / "x_e1.png")});
  const MetricList aligned =
      AlignedHdrMetrics(ReadImage(dir / "pred" / "x.exr"), ReadImage(dir / "gt" / "x.exr"), &mask);
  for (const auto& [key, value] : aligned)
    EXPECT_DOUBLE_EQ(with["pairs"][0][key].get<double>(), value) << key;
  // Brackets of another size are an error naming the HDR file.
  WriteImage(dir / "small.png", Image(4, 4, 3, Encoding::kSrgb));
  const EvalBrackets wrong = {{"x.exr", {dir / "small.png"}}};
  EXPECT_THAT(ErrorOf([&] { EvaluatePaths(dir / "pred", dir / "gt", &wrong); }),
              HasSubstr("x.exr: its LDR brackets are not the size"));
}

// With ldr_fit and the renders of the brackets beside the HDR prediction, the HDR's shape where
// they reproduce their bracket; without either, no such keys.
TEST(EvaluateTest, RenderedBracketsGiveTheShapeWhereTheLdrFits) {
  TempDir dir;
  const int w = 16, h = 8;
  Image gt(w, h, 3, Encoding::kLinear), pred(w, h, 3, Encoding::kLinear);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) {
        gt.at(x, y, c) = float(std::pow(10.0, -2.0 + 3.0 * (x + w * y) / (w * h)));
        pred.at(x, y, c) = float(std::sqrt(gt.at(x, y, c)));  // the truth to the power 0.5
      }
  WriteImage(dir / "gt" / "x.exr", gt);
  WriteImage(dir / "pred" / "x.exr", pred);
  // Two brackets; the render of the first is right on the top half only, the second is absent.
  Image e0(w, h, 3, Encoding::kSrgb), e1(w, h, 3, Encoding::kSrgb);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c) {
        e0.at(x, y, c) = std::min(1.0f, std::pow(gt.at(x, y, c) * 0.1f, 1 / 2.2f));
        e1.at(x, y, c) = std::min(1.0f, std::pow(gt.at(x, y, c) * 10.0f, 1 / 2.2f));
      }
  WriteImage(dir / "x_e0.png", e0);
  WriteImage(dir / "x_e1.png", e1);
  Image render = e0;
  for (int y = h / 2; y < h; ++y)
    for (int x = 0; x < w; ++x) render.at(x, y, 1) = 0.0f;
  WriteImage(dir / "pred" / "x_e0.png", render);
  const EvalBrackets brackets = {{"x.exr", {dir / "x_e0.png", dir / "x_e1.png"}}};
  const nlohmann::json fit = EvaluatePaths(dir / "pred", dir / "gt", &brackets, 1, true);
  const nlohmann::json plain = EvaluatePaths(dir / "pred", dir / "gt", &brackets);
  ASSERT_EQ(fit["pairs"].size(), 1u) << fit.dump();  // the LDR render has no LDR truth to pair
  const nlohmann::json& pair = fit["pairs"][0];
  ASSERT_TRUE(pair.contains("hdr_log_slope_ldr_fit")) << fit.dump();
  EXPECT_NEAR(pair["hdr_log_slope_ldr_fit"].get<double>(), 0.5, 1e-3);
  const std::vector<std::uint8_t> measured =
      MeasurableInBrackets({ReadImage(dir / "x_e0.png"), ReadImage(dir / "x_e1.png")});
  const std::vector<std::uint8_t> reproduced =
      ReproducedInBrackets({ReadImage(dir / "x_e0.png")}, {ReadImage(dir / "pred" / "x_e0.png")});
  for (const auto& [key, value] :
       LdrFitHdrShape(ReadImage(dir / "pred" / "x.exr"), ReadImage(dir / "gt" / "x.exr"), measured,
                      reproduced)) {
    EXPECT_DOUBLE_EQ(pair[key].get<double>(), value) << key;
    EXPECT_NEAR(fit["mean"][key].get<double>(), value, 1e-12) << key;  // one image: pooled = it
  }
  EXPECT_LT(pair["hdr_ldr_fit_fraction"].get<double>(), 0.5);  // only the top half fits
  EXPECT_FALSE(plain["pairs"][0].contains("hdr_log_slope_ldr_fit")) << plain.dump();
  // A render that cannot be read is an error naming it.
  testing::WriteTextFile(dir / "pred" / "x_e0.png", "not a png");
  EXPECT_THAT(ErrorOf([&] { EvaluatePaths(dir / "pred", dir / "gt", &brackets, 1, true); }),
              HasSubstr("x_e0.png"));
}

TEST(EvaluateTest, MixedFolderMeansEachKeyOverItsPairs) {
  TempDir dir;
  WriteLdr(dir / "gt" / "a.png", 8, 8, 8);
  WriteLdr(dir / "pred" / "a.png", 8, 8, 9);
  WriteHdr(dir / "gt" / "h.exr", 8, 8, 10);
  WriteHdr(dir / "pred" / "h.exr", 8, 8, 11);
  const nlohmann::json result = EvaluatePaths(dir / "pred", dir / "gt");
  ASSERT_EQ(result["pairs"].size(), 2u);
  EXPECT_EQ(KeysOf(result["pairs"][0]), kLdrKeys);
  EXPECT_EQ(KeysOf(result["pairs"][1]), kHdrKeys);
  EXPECT_EQ(result["mean"]["psnr"], result["pairs"][0]["psnr"]);
  EXPECT_EQ(result["mean"]["pu21_psnr"], result["pairs"][1]["pu21_psnr"]);
  EXPECT_EQ(KeysOf(result["mean"]).size(), kLdrKeys.size() + kHdrKeys.size() - 2);

  const std::string table = FormatEvalTable(result);
  EXPECT_THAT(table, HasSubstr("pu21_psnr"));
  EXPECT_THAT(table, HasSubstr(" - "));  // the LDR pair has no HDR keys and vice versa
}

// Issue 11, case 11: one identical pair (PSNR +inf) used to make every PSNR mean null (inf in the
// table), hiding the other pairs' values.
TEST(EvaluateTest, IdenticalImagesWriteNullAndParse) {
  TempDir dir;
  WriteLdr(dir / "gt" / "a.png", 10, 10, 12);
  fs::create_directories(dir / "pred");
  fs::copy_file(dir / "gt" / "a.png", dir / "pred" / "a.png");
  WriteLdr(dir / "gt" / "b.png", 10, 10, 13);
  WriteLdr(dir / "pred" / "b.png", 10, 10, 14);
  const nlohmann::json result = EvaluatePaths(dir / "pred", dir / "gt");
  EXPECT_TRUE(result["pairs"][0]["psnr"].is_null());
  EXPECT_TRUE(result["pairs"][0]["psnr_channel_mean"].is_null());
  EXPECT_NEAR(result["pairs"][0]["ssim"].get<double>(), 1.0, 1e-12);
  EXPECT_TRUE(result["pairs"][1]["psnr"].is_number());
  // The mean is over the finite values (here the other pair's), the identical pair is counted.
  EXPECT_EQ(result["mean"]["psnr"], result["pairs"][1]["psnr"]);
  EXPECT_EQ(result["mean"]["psnr_channel_mean"], result["pairs"][1]["psnr_channel_mean"]);
  EXPECT_NEAR(result["mean"]["ssim"].get<double>(),
              (1.0 + result["pairs"][1]["ssim"].get<double>()) / 2, 1e-12);
  EXPECT_EQ(result["identical_pairs"], 1);
  const std::string text = result.dump();
  EXPECT_THAT(text, Not(HasSubstr("inf")));
  EXPECT_EQ(nlohmann::json::parse(text), result);

  const std::string table = FormatEvalTable(result);
  EXPECT_THAT(table, HasSubstr("inf"));
  EXPECT_THAT(table, HasSubstr("\nmean "));
  EXPECT_THAT(table, HasSubstr("identical: 1 of 2 pairs"));
  EXPECT_EQ(std::count(table.begin(), table.end(), '\n'), 5);  // header, 2 pairs, mean, count

  // Every pair identical: no finite PSNR to average, so the mean is null, not a made-up number.
  const nlohmann::json all_same = EvaluatePaths(dir / "gt" / "a.png", dir / "pred" / "a.png");
  EXPECT_TRUE(all_same["mean"]["psnr"].is_null());
  EXPECT_EQ(all_same["identical_pairs"], 1);
}

// The sweep of session 94: one channel the same in both images makes psnr_channel_mean +inf (as
// the reference's per-channel mean does) on a pair that is not identical; it was left out of the
// mean without a word. The result and the table count it.
TEST(EvaluateTest, AnInfiniteValueOfAPairThatDiffersIsCounted) {
  TempDir dir;
  Image pred = RandomImage(6, 6, 3, 40, 0, 1, Encoding::kSrgb);
  Image gt = pred;
  for (std::size_t p = 0; p < gt.num_pixels(); ++p) {  // red and green differ, blue does not
    for (int c = 0; c < 2; ++c)
      gt.values()[p * 3 + c] = std::round(gt.values()[p * 3 + c] * 100) / 255;
  }
  WriteImage(dir / "pred" / "a.png", pred);
  WriteImage(dir / "gt" / "a.png", gt);
  WriteLdr(dir / "gt" / "b.png", 6, 6, 41);
  WriteLdr(dir / "pred" / "b.png", 6, 6, 42);
  const nlohmann::json result = EvaluatePaths(dir / "pred", dir / "gt");
  EXPECT_TRUE(result["pairs"][0]["psnr"].is_number());
  EXPECT_TRUE(result["pairs"][0]["psnr_channel_mean"].is_null());
  EXPECT_EQ(result["identical_pairs"], 0);
  EXPECT_EQ(result["infinite_left_out"], (nlohmann::json{{"psnr_channel_mean", 1}}));
  EXPECT_EQ(result["mean"]["psnr_channel_mean"], result["pairs"][1]["psnr_channel_mean"]);
  EXPECT_THAT(FormatEvalTable(result),
              HasSubstr("psnr_channel_mean: inf on 1 pair not identical (a channel is), left out "
                        "of its mean"));
}

TEST(EvaluateTest, TableShowsValuesWithFourDecimals) {
  nlohmann::json result = {{"pairs", {{{"name", "x.png"}, {"psnr", 31.123456}, {"ssim", 0.9}}}},
                           {"mean", {{"psnr", 31.123456}, {"ssim", 0.9}}}};
  const std::string table = FormatEvalTable(result);
  EXPECT_THAT(table, HasSubstr("31.1235"));
  EXPECT_THAT(table, HasSubstr("0.9000"));
  EXPECT_LT(table.find("psnr"), table.find("ssim"));
  EXPECT_THAT(ErrorOf([] { FormatEvalTable(nlohmann::json::object()); }), HasSubstr("pairs"));
}

TEST(EvaluateTest, AcceptsSameStemOfTheSameKind) {
  TempDir dir;
  WriteLdr(dir / "gt" / "r_000.png", 8, 6, 15);
  WriteLdr(dir / "pred" / "r_000.jpg", 8, 6, 16);
  const nlohmann::json result = EvaluatePaths(dir / "pred", dir / "gt");
  ASSERT_EQ(result["pairs"].size(), 1u);
  EXPECT_EQ(result["pairs"][0]["name"], "r_000.png");
  EXPECT_EQ(KeysOf(result["pairs"][0]), kLdrKeys);
}

TEST(EvaluateTest, AmbiguousStemIsAnError) {
  TempDir dir;
  WriteLdr(dir / "pred" / "r_000.png", 8, 6, 17);
  WriteLdr(dir / "gt" / "r_000.jpg", 8, 6, 18);
  WriteLdr(dir / "gt" / "r_000.jpeg", 8, 6, 19);
  const std::string error = ErrorOf([&] { EvaluatePaths(dir / "pred", dir / "gt"); });
  EXPECT_THAT(error, HasSubstr("several ground-truth images match prediction r_000.png"));
  EXPECT_THAT(error, HasSubstr("r_000.jpeg"));
}

TEST(EvaluateTest, PredictionWithoutGroundTruthNamesTheFile) {
  LdrFolders f;
  WriteLdr(f.pred / "c.png", 16, 12, 20);
  WriteLdr(f.pred / "d.png", 16, 12, 21);
  WriteHdr(f.gt / "d.exr", 16, 12, 22);  // same stem, other kind: not a match
  const std::string error = ErrorOf([&] { EvaluatePaths(f.pred, f.gt); });
  EXPECT_THAT(error, HasSubstr("no ground truth for 2 of 4 predicted images"));
  EXPECT_THAT(error, HasSubstr("c.png"));
  EXPECT_THAT(error, HasSubstr("d.png (only d.exr found, which is HDR)"));
  EXPECT_THAT(error, HasSubstr(f.gt.string()));
}

TEST(EvaluateTest, RenderFolderWithBothKindsScoresAgainstEachGroundTruthFolder) {
  TempDir dir;
  // A render folder holds r.png and r.exr; the dataset keeps images/ and hdr/ apart.
  WriteLdr(dir / "pred" / "r.png", 8, 6, 1);
  WriteHdr(dir / "pred" / "r.exr", 8, 6, 2);
  WriteLdr(dir / "images" / "r.png", 8, 6, 3);
  WriteHdr(dir / "hdr" / "r.exr", 8, 6, 4);
  const nlohmann::json ldr = EvaluatePaths(dir / "pred", dir / "images");
  EXPECT_EQ(ldr["pairs"].size(), 1u);
  EXPECT_TRUE(ldr["mean"].contains("psnr"));
  const nlohmann::json hdr = EvaluatePaths(dir / "pred", dir / "hdr");
  EXPECT_EQ(hdr["pairs"].size(), 1u);
  EXPECT_TRUE(hdr["mean"].contains("mu_psnr"));
  // Nothing of the ground truth's kind among the predictions: an error, not an empty score.
  fs::remove(dir / "pred" / "r.exr");
  EXPECT_THAT(ErrorOf([&] { EvaluatePaths(dir / "pred", dir / "hdr"); }),
              HasSubstr("holds only HDR images"));
}

TEST(EvaluateTest, ListsOnlyTheFirstUnmatchedNames) {
  TempDir dir;
  for (int i = 0; i < 8; ++i) WriteLdr(dir / "pred" / fmt::format("m{}.png", i), 4, 4, i);
  fs::create_directories(dir / "gt");
  const std::string error = ErrorOf([&] { EvaluatePaths(dir / "pred", dir / "gt"); });
  EXPECT_THAT(error, HasSubstr("no ground truth for 8 of 8"));
  EXPECT_THAT(error, HasSubstr("m4.png, ... (3 more)"));
  EXPECT_THAT(error, Not(HasSubstr("m7.png")));
}

TEST(EvaluateTest, EmptyPredictionFolderIsAnError) {
  TempDir dir;
  testing::WriteTextFile(dir / "pred" / "readme.txt", "x");
  WriteLdr(dir / "gt" / "a.png", 4, 4, 1);
  EXPECT_THAT(ErrorOf([&] { EvaluatePaths(dir / "pred", dir / "gt"); }),
              HasSubstr("no predicted images"));
}

TEST(EvaluateTest, MixedLdrHdrPairNamesBothFiles) {
  TempDir dir;
  WriteHdr(dir / "pred.exr", 8, 8, 23);
  WriteLdr(dir / "gt.png", 8, 8, 24);
  const std::string error = ErrorOf([&] { EvaluatePaths(dir / "pred.exr", dir / "gt.png"); });
  EXPECT_THAT(error, HasSubstr((dir / "pred.exr").string()));
  EXPECT_THAT(error, HasSubstr((dir / "gt.png").string()));
  EXPECT_THAT(error, HasSubstr("LDR image with an HDR one"));
}

TEST(EvaluateTest, SizeMismatchNamesFilesAndShapes) {
  TempDir dir;
  WriteLdr(dir / "pred.png", 5, 3, 25);
  WriteLdr(dir / "gt.png", 4, 3, 26);
  const std::string error = ErrorOf([&] { EvaluatePair(dir / "pred.png", dir / "gt.png"); });
  EXPECT_THAT(error, HasSubstr((dir / "pred.png").string() + " (5x3x3)"));
  EXPECT_THAT(error, HasSubstr((dir / "gt.png").string() + " (4x3x3)"));
  EXPECT_THAT(error, HasSubstr("differ in size"));
}

TEST(EvaluateTest, ChannelMismatchIsAnErrorButAlphaIsIgnored) {
  TempDir dir;
  WriteImage(dir / "grey.png", RandomImage(4, 4, 1, 27, 0, 1, Encoding::kSrgb));
  WriteImage(dir / "rgba.png", RandomImage(4, 4, 4, 28, 0, 1, Encoding::kSrgb));
  WriteLdr(dir / "rgb.png", 4, 4, 29);
  EXPECT_THAT(ErrorOf([&] { EvaluatePair(dir / "grey.png", dir / "rgb.png"); }),
              HasSubstr("colour channels (1 vs 3)"));
  // A grey truth against an RGB render (a grey scene trains as RGB): the truth read as RGB.
  WriteImage(dir / "grey_as_rgb.png", ExpandToRgb(ReadImage(dir / "grey.png")));
  EXPECT_EQ(EvaluatePair(dir / "rgb.png", dir / "grey.png")["psnr"],
            EvaluatePair(dir / "rgb.png", dir / "grey_as_rgb.png")["psnr"]);
  const nlohmann::json pair = EvaluatePair(dir / "rgba.png", dir / "rgb.png");
  EXPECT_EQ(pair["name"], "rgb.png");
  EXPECT_EQ(KeysOf(pair), kLdrKeys);
  // Grey + alpha is grey: the same grey under alpha 0 and alpha 1 is the same image (its alpha
  // was scored as a second colour channel: PSNR 3 dB).
  Image transparent = RandomImage(4, 4, 2, 30, 0, 1, Encoding::kSrgb);
  Image opaque = transparent;
  for (std::size_t p = 0; p < transparent.num_pixels(); ++p) {
    transparent.values()[p * 2 + 1] = 0.0f;
    opaque.values()[p * 2 + 1] = 1.0f;
  }
  WriteImage(dir / "ga0.png", transparent);
  WriteImage(dir / "ga1.png", opaque);
  const nlohmann::json grey_pair = EvaluatePair(dir / "ga0.png", dir / "ga1.png");
  EXPECT_TRUE(grey_pair["psnr"].is_null()) << grey_pair;  // identical: +inf
  EXPECT_NEAR(grey_pair["ssim"].get<double>(), 1.0, 1e-12);
  EXPECT_EQ(ErrorOf([&] { EvaluatePair(dir / "ga0.png", dir / "grey.png"); }), "");
  EXPECT_THAT(ErrorOf([&] { EvaluatePair(dir / "ga0.png", dir / "rgb.png"); }),
              HasSubstr("colour channels (1 vs 3)"));
}

TEST(EvaluateTest, BlackHdrGroundTruthNamesTheFiles) {
  TempDir dir;
  WriteImage(dir / "gt.exr", Image(6, 6, 3), {.format = PixelFormat::kFloat});
  WriteHdr(dir / "pred.exr", 6, 6, 30);
  const std::string error = ErrorOf([&] { EvaluatePair(dir / "pred.exr", dir / "gt.exr"); });
  EXPECT_THAT(error, HasSubstr((dir / "gt.exr").string()));
  EXPECT_THAT(error, HasSubstr("all black"));
}

TEST(EvaluateTest, BadPathsAreErrors) {
  TempDir dir;
  WriteLdr(dir / "a.png", 4, 4, 31);
  fs::create_directories(dir / "folder");
  EXPECT_THAT(ErrorOf([&] { EvaluatePaths(dir / "nope.png", dir / "a.png"); }),
              HasSubstr((dir / "nope.png").string() + ": not found"));
  EXPECT_THAT(ErrorOf([&] { EvaluatePaths(dir / "a.png", dir / "folder"); }),
              HasSubstr("give two image files or two folders"));
  EXPECT_THAT(ErrorOf([&] { EvaluatePair(dir / "a.png", dir / "missing.png"); }),
              HasSubstr("missing.png"));
}

TEST(EvaluateTest, FirstFailingPairInNameOrderIsReported) {
  TempDir dir;
  for (const std::string name : {"a.png", "b.png", "c.png"}) WriteLdr(dir / "gt" / name, 4, 4, 32);
  WriteLdr(dir / "pred" / "a.png", 4, 4, 33);
  WriteLdr(dir / "pred" / "b.png", 5, 4, 34);
  WriteLdr(dir / "pred" / "c.png", 6, 4, 35);
  const std::string error = ErrorOf([&] { EvaluatePaths(dir / "pred", dir / "gt"); });
  EXPECT_THAT(error, HasSubstr("b.png (5x4x3)"));
  EXPECT_THAT(error, HasSubstr("(and 1 more pairs failed)"));
}

TEST(EvaluateTest, SameResultAtAnyThreadCount) {
  LdrFolders f;
  const nlohmann::json parallel = EvaluatePaths(f.pred, f.gt);
  ThreadLimit one(1);
  EXPECT_EQ(EvaluatePaths(f.pred, f.gt), parallel);
}

// ---- The CLI ---------------------------------------------------------------------------------

TEST(EvalCommandTest, JsonOutputParsesAndMatchesTheLibrary) {
  LdrFolders f;
  const auto r = RunHdr4d("eval '" + f.pred.string() + "' '" + f.gt.string() + "' --json --out '" +
                          (f.dir / "out" / "eval.json").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json printed = nlohmann::json::parse(r.out);
  const nlohmann::json expected = EvaluatePaths(f.pred, f.gt);
  EXPECT_EQ(printed, expected);
  EXPECT_EQ(nlohmann::json::parse(testing::ReadTextFile(f.dir / "out" / "eval.json")), expected);
}

TEST(EvalCommandTest, TableByDefault) {
  LdrFolders f;
  const auto r =
      RunHdr4d("eval '" + (f.pred / "a.png").string() + "' '" + (f.gt / "a.png").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("psnr_channel_mean"));
  EXPECT_THAT(r.out, HasSubstr("\nmean "));
}

TEST(EvalCommandTest, MissingPathFailsWithOneLine) {
  TempDir dir;
  WriteLdr(dir / "gt.png", 4, 4, 36);
  const std::string missing = (dir / "missing.png").string();
  const auto r = RunHdr4d("eval '" + missing + "' '" + (dir / "gt.png").string() + "' --json");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_THAT(r.err, HasSubstr(missing));
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
  EXPECT_TRUE(r.out.empty());
}

TEST(EvalCommandTest, HelpExplainsTheProtocol) {
  const auto r = RunHdr4d("eval --help");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_THAT(r.out, HasSubstr("4000"));
  EXPECT_THAT(r.out, HasSubstr("own max"));
  EXPECT_THAT(r.out, HasSubstr("same file name"));
}


// --resolution R scores the renders of a run trained at 1/R: the ground truth is box-averaged
// (HDR) and, for LDR, quantised as the training targets are; an R that does not divide it names
// the file.
TEST(EvaluateTest, ResolutionReducesTheGroundTruthAsTrainingDid) {
  TempDir dir;
  WriteHdr(dir / "gt.exr", 8, 6, 1);
  WriteImage(dir / "pred.exr", DownsampleBox(ReadImage(dir / "gt.exr"), 2),
             {.format = PixelFormat::kFloat});
  EXPECT_EQ(EvaluatePair(dir / "pred.exr", dir / "gt.exr", nullptr, 2)["mu_psnr"], nullptr)
      << "identical after the reduction: infinite PSNR";
  WriteLdr(dir / "gt.png", 8, 6, 2);
  Image reduced = DownsampleBox(ReadImage(dir / "gt.png"), 2);
  WriteImage(dir / "pred.png", reduced);
  // The same 8-bit values (up to float rounding of k / 255).
  const nlohmann::json ldr = EvaluatePair(dir / "pred.png", dir / "gt.png", nullptr, 2)["psnr"];
  EXPECT_TRUE(ldr.is_null() || ldr.get<double>() > 100) << ldr;
  const std::string m = ErrorOf([&] { EvaluatePair(dir / "pred.png", dir / "gt.png", nullptr, 4); });
  EXPECT_NE(m.find("gt.png: 8x6 is not divisible by --resolution 4"), std::string::npos) << m;
}

}  // namespace
}  // namespace hdr4d
