#include "core/viz/preview.h"

#include <gtest/gtest.h>

#include "core/dataset/demo_scene.h"
#include "core/image/image_io.h"
#include "core/util/error.h"
#include "core/radiometry/exposure_stack.h"
#include "tests/testing.h"

namespace hdr4d {
namespace {

TEST(Preview, TileImagesPlacesEachImageInItsCell) {
  Image a(2, 2, 3, Encoding::kSrgb, 0.25f), b(2, 2, 1, Encoding::kSrgb, 0.75f);
  const Image sheet = TileImages({{a, b}, {b}}, 1, 0.0f);
  EXPECT_EQ(sheet.width(), 2 * 2 + 3);
  EXPECT_EQ(sheet.height(), 2 * 2 + 3);
  EXPECT_FLOAT_EQ(sheet.at(1, 1, 0), 0.25f);  // a at row 0, column 0
  EXPECT_FLOAT_EQ(sheet.at(4, 1, 2), 0.75f);  // b (grey) at row 0, column 1
  EXPECT_FLOAT_EQ(sheet.at(1, 4, 1), 0.75f);  // b at row 1, column 0
  EXPECT_FLOAT_EQ(sheet.at(4, 4, 0), 0.0f);   // empty cell stays background
  EXPECT_FLOAT_EQ(sheet.at(0, 0, 0), 0.0f);   // padding
  EXPECT_THROW(TileImages({{a, Image(3, 2, 3)}}), Error);
  EXPECT_THROW(TileImages({}), Error);
}

TEST(Preview, DisplayHdrMapsMaxToOne) {
  Image hdr(2, 1, 3, Encoding::kLinear);
  hdr.values() = {0, 0, 0, 100, 50, 1};
  const Image shown = DisplayHdr(hdr);
  EXPECT_FLOAT_EQ(shown.at(1, 0, 0), 1.0f);
  EXPECT_FLOAT_EQ(shown.at(0, 0, 0), 0.0f);
  EXPECT_GT(shown.at(1, 0, 2), 0.0f);
  EXPECT_LT(shown.at(1, 0, 2), shown.at(1, 0, 1));
  EXPECT_THROW(DisplayHdr(Image(2, 2, 3)), Error);  // all black: nothing to normalise by
}

TEST(Preview, DatasetSheetHasARowPerExposurePlusHdr) {
  testing::TempDir dir;
  DemoSceneOptions options;
  options.width = options.height = 16;
  options.num_timestamps = 5;
  options.num_cameras = 2;
  options.samples_per_axis = 1;
  const Dataset dataset = MakeDemoScene(options, dir.path());
  SynthesizeDatasetLdr(dir.path(), {});
  const Preview preview =
      MakeDatasetPreview(LoadDataset(dir.path()), {.split = "test", .max_columns = 3});
  ASSERT_EQ(preview.row_labels.size(), 4u);  // 3 exposures + HDR
  ASSERT_EQ(preview.column_times.size(), 3u);
  EXPECT_DOUBLE_EQ(preview.column_times.front(), 0.0);
  EXPECT_DOUBLE_EQ(preview.column_times.back(), 1.0);
  EXPECT_EQ(preview.sheet.width(), 3 * 16 + 4 * 2);
  EXPECT_EQ(preview.sheet.height(), 4 * 16 + 5 * 2);
  EXPECT_THROW(MakeDatasetPreview(dataset, {.split = "test", .camera_id = 7}), Error);
  EXPECT_THROW(MakeDatasetPreview(dataset, {.split = "val"}), Error);
  EXPECT_THROW(MakeDatasetPreview(dataset, {.split = "nope"}), Error);

  // The sweep of session 94: a grey LDR image and an all-black HDR image. The grey one is shown;
  // the black one is refused naming its file (it said "the image has no positive finite maximum").
  const Frame& first = dataset.test.front();
  WriteImage(first.image_path, Image(16, 16, 1, Encoding::kSrgb, 0.5f));
  EXPECT_NO_THROW(MakeDatasetPreview(LoadDataset(dir.path()), {.split = "test"}));
  WriteImage(*first.hdr_path, Image(16, 16, 3, Encoding::kLinear, 0.0f),
             {.format = PixelFormat::kFloat});
  const std::string error = testing::ErrorOf(
      [&] { MakeDatasetPreview(dataset, {.split = "test", .camera_id = first.camera_id}); });
  EXPECT_NE(error.find(first.hdr_path->string() + ": has no positive value"), std::string::npos)
      << error;
}

}  // namespace
}  // namespace hdr4d
