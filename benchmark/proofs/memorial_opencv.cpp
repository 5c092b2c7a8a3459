// The OpenCV reference numbers of calibration/hdr_fusion_test.cpp's Memorial test (issue 54),
// measured outside hdr4d (OpenCV is not a dependency of the merge):
//   g++ -O2 -o /tmp/memorial_opencv benchmark/proofs/memorial_opencv.cpp $(pkg-config --cflags --libs opencv4)
//   /tmp/memorial_opencv ../shared/data/memorial_exposures
// Prints the rose window / dark wall ratio of OpenCV's MergeDebevec and MergeRobertson (each
// with its own Calibrate* response), and of OpenCV's Debevec response merged the way
// MergeDebevec does (triangle weights, log domain) but with codes within three noise widths of
// the black level weighted out: what MergeDebevec gives once its shadows are not lifted by the
// short brackets' black codes.
#include <opencv2/opencv.hpp>
#include <opencv2/photo.hpp>

#include <cmath>
#include <fstream>
#include <iostream>

namespace {

const cv::Rect kWindow(160, 120, 45, 45), kWall(400, 150, 80, 100);

double Ratio(const cv::Mat& hdr) {
  const cv::Scalar a = cv::mean(hdr(kWindow)), b = cv::mean(hdr(kWall));
  return (a[0] + a[1] + a[2]) / (b[0] + b[1] + b[2]);
}

// MergeDebevec's formula with weights that are 0 up to black + 3 sigma and rise over 4 sigma + 4.
cv::Mat MergeAboveBlack(const std::vector<cv::Mat>& images, const std::vector<float>& times,
                        const cv::Mat& response, double black, double sigma) {
  cv::Mat out(images[0].rows, images[0].cols, CV_32FC3);
  for (int y = 0; y < out.rows; ++y)
    for (int x = 0; x < out.cols; ++x)
      for (int c = 0; c < 3; ++c) {
        double sum = 0, den = 0;
        for (std::size_t j = 0; j < images.size(); ++j) {
          const int z = images[j].at<cv::Vec3b>(y, x)[c];
          const double lo = black + 3 * sigma, t = std::clamp((z - lo) / (4 * sigma + 4), 0.0, 1.0);
          const double w = t * t * (3 - 2 * t) * (z < 128 ? z + 1 : 256 - z);
          sum += w * (std::log(response.at<cv::Vec3f>(z)[c]) - std::log(times[j]));
          den += w;
        }
        out.at<cv::Vec3f>(y, x)[c] = den > 0 ? static_cast<float>(std::exp(sum / den)) : 0.0f;
      }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string dir = argc > 1 ? std::string(argv[1]) + "/" : "../shared/data/memorial_exposures/";
  std::ifstream list(dir + "list.txt");
  if (!list) {
    std::cerr << dir << "list.txt: not found\n";
    return 1;
  }
  std::vector<cv::Mat> images;
  std::vector<float> times;
  std::string file;
  float seconds;
  while (list >> file >> seconds) images.push_back(cv::imread(dir + file)), times.push_back(seconds);
  cv::Mat debevec, robertson, hdr;
  cv::createCalibrateDebevec()->process(images, debevec, times);
  cv::createMergeDebevec()->process(images, hdr, times, debevec);
  std::cout << "MergeDebevec " << Ratio(hdr) << "\n";
  cv::createCalibrateRobertson()->process(images, robertson, times);
  cv::createMergeRobertson()->process(images, hdr, times, robertson);
  std::cout << "MergeRobertson " << Ratio(hdr) << "\n";
  for (double black : {16.0, 19.0})
    std::cout << "MergeDebevec's formula, codes near black " << black << " (sigma 1.5) weighted out "
              << Ratio(MergeAboveBlack(images, times, debevec, black, 1.5)) << "\n";
}
