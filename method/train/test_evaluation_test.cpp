#include "method/train/test_evaluation.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <vector>

#include "core/dataset/dataset.h"
#include "method/train/tiny_run_test_util.h"
#include "tests/testing.h"

namespace hdr4d::method {
namespace {
using hdr4d::testing::TempDir;

// The held-out views of a tiny HDR scene (three brackets share each HDR truth), sorted by
// exposure so that the bracket groups interleave: EvaluateViews adds the views group by group,
// not in the split's order, and MeanLdrPsnr must add them the same way to give the same sum.
std::vector<TrainView> InterleavedBrackets(const std::filesystem::path& root) {
  train_testing::MakeTinyHdrScene(root, 16);
  const float black[3] = {0, 0, 0};
  std::vector<TrainView> views = CheckViews(LoadDataset(root), Split::kTest, black);
  std::stable_sort(views.begin(), views.end(),
                   [](const TrainView& a, const TrainView& b) { return a.exposure < b.exposure; });
  return views;
}

// The val stop reads MeanLdrPsnr: EvaluateViews's "psnr" bit for bit, without an HDR render.
// Each view renders as its truth darkened by its own amount, one view exactly (an infinite
// PSNR, left out of both means).
TEST(MeanLdrPsnr, IsEvaluateViewsPsnrBitForBit) {
  TempDir dir;
  const std::vector<TrainView> views = InterleavedBrackets(dir / "scene");
  ASSERT_GE(views.size(), 6u);
  ASSERT_TRUE(views[0].has_hdr());
  ASSERT_NE(views[0].hdr_path, views[1].hdr_path);  // the groups interleave
  int hdr_renders = 0;
  const RenderViewFn render = [&](const TrainView& v, std::vector<float>* ldr,
                                  std::vector<float>* hdr) {
    const std::size_t k = static_cast<std::size_t>(&v - views.data());
    v.ToFloat(ldr);
    if (k != 2) {
      for (float& x : *ldr) x *= 0.9f - 0.013f * static_cast<float>(k);
    }
    if (hdr) {
      ++hdr_renders;
      hdr->assign(ldr->size(), 0.25f + 0.01f * static_cast<float>(k));
    }
  };
  const nlohmann::json all = EvaluateViews(render, views, /*with_flip=*/false);
  ASSERT_GT(hdr_renders, 0);
  hdr_renders = 0;
  const double psnr = MeanLdrPsnr(render, views);
  EXPECT_EQ(hdr_renders, 0);
  EXPECT_EQ(psnr, all.at("psnr").get<double>());

  // And it is the mean of the views' own PSNRs, the exact view left out.
  double sum = 0;
  int count = 0;
  std::vector<float> ldr, gt;
  for (const TrainView& v : views) {
    render(v, &ldr, nullptr);
    v.ToFloat(&gt);
    double squared = 0;
    for (std::size_t i = 0; i < ldr.size(); ++i) {
      const double d = static_cast<double>(ldr[i]) - gt[i];
      squared += d * d;
    }
    if (squared == 0) continue;
    sum += 10 * std::log10(ldr.size() / squared);
    ++count;
  }
  EXPECT_NEAR(psnr, sum / count, 1e-6);
}

// Every view rendered exactly: no finite PSNR, so EvaluateViews has no "psnr" and MeanLdrPsnr
// is NaN (the val curve then records null, as before).
TEST(MeanLdrPsnr, IsNanWhereNoViewHasAFinitePsnr) {
  TempDir dir;
  const std::vector<TrainView> views = InterleavedBrackets(dir / "scene");
  const RenderViewFn exact = [](const TrainView& v, std::vector<float>* ldr,
                                std::vector<float>* hdr) {
    v.ToFloat(ldr);
    if (hdr) hdr->assign(ldr->size(), 1.0f);
  };
  EXPECT_FALSE(EvaluateViews(exact, views, /*with_flip=*/false).contains("psnr"));
  EXPECT_TRUE(std::isnan(MeanLdrPsnr(exact, views)));
  EXPECT_TRUE(std::isnan(MeanLdrPsnr(exact, {})));
}

}  // namespace
}  // namespace hdr4d::method
