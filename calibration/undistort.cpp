#include "calibration/undistort.h"

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace hdr4d {

double MaxDistortionPixels(const BundleIntrinsics& k, int width, int height) {
  if (!(k.f > 0)) return 0;
  double worst = 0;
  // Radial distortion grows (for moderate k) towards the corners; sample the border densely.
  for (int i = 0; i <= 64; ++i) {
    const double s = i / 64.0;
    for (const auto& [u, v] : {std::pair{s * width, 0.0}, {s * width, double(height)},
                               {0.0, s * height}, {double(width), s * height}}) {
      const double x = (u - k.cx) / k.f, y = (v - k.cy) / k.f, r2 = x * x + y * y;
      worst = std::max(worst, k.f * std::sqrt(r2) * std::abs(k.k1 * r2 + k.k2 * r2 * r2));
    }
  }
  return worst;
}

Image Undistort(const Image& image, const BundleIntrinsics& k) {
  const cv::Vec4d distortion(k.k1, k.k2, 0, 0);
  cv::Mat map_x, map_y;
  // OpenCV's pixel centres are at integers, ours at +0.5: shift the principal point for it.
  const cv::Matx33d cv_camera(k.f, 0, k.cx - 0.5, 0, k.f, k.cy - 0.5, 0, 0, 1);
  cv::initUndistortRectifyMap(cv_camera, distortion, cv::noArray(), cv_camera,
                              cv::Size(image.width(), image.height()), CV_32FC1, map_x, map_y);
  const cv::Mat src(image.height(), image.width(), CV_32FC(image.channels()),
                    const_cast<float*>(image.data()));
  Image out(image.width(), image.height(), image.channels(), image.encoding());
  cv::Mat dst(out.height(), out.width(), CV_32FC(out.channels()), out.data());
  cv::remap(src, dst, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  return out;
}

}  // namespace hdr4d
