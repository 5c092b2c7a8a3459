// The OpenCV reference numbers of calibration/hdr_fusion_test.cpp's Memorial test (issue 54),
// measured outside hdr4d (OpenCV is not a dependency of the merge):
//   g++ -O2 -o /tmp/memorial_opencv benchmark/proofs/memorial_opencv.cpp $(pkg-config --cflags --libs opencv4)
//   /tmp/memorial_opencv ../shared/data/memorial_exposures [OURS.exr ...]
// (reading EXR needs OPENCV_IO_ENABLE_OPENEXR=1 in the environment)
// Prints the rose window / dark wall ratio of OpenCV's MergeDebevec and MergeRobertson (each
// with its own Calibrate* response), and of OpenCV's Debevec response merged the way
// MergeDebevec does (triangle weights, log domain) but with codes within three noise widths of
// the black level weighted out: what MergeDebevec gives once its shadows are not lifted by the
// short brackets' black codes. And the ratio from one bracket per region (the one that
// exposes it best), which no weighting or black code enters, under our boxes and under the
// issue's candidate definitions.
#include <opencv2/opencv.hpp>
#include <opencv2/photo.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iostream>
#include <vector>

namespace {

const cv::Rect kWindow(160, 120, 45, 45), kWall(400, 150, 80, 100);

// Window over wall, each the mean of its box in RGB (read from two images where they differ).
double Ratio(const cv::Mat& window_image, const cv::Mat& wall_image) {
  const cv::Scalar a = cv::mean(window_image(kWindow)), b = cv::mean(wall_image(kWall));
  return (a[0] + a[1] + a[2]) / (b[0] + b[1] + b[2]);
}
double Ratio(const cv::Mat& hdr) { return Ratio(hdr, hdr); }

// The issue's 1328 (MergeDebevec) and 1594 (MergeRobertson) came from region boxes it did not
// record. These four definitions each give both within 3% (of 71 found by scanning box positions
// and sizes, mean or median, RGB mean or green): the candidates for "the issue's definition".
struct RegionDefinition {
  const char* name;
  cv::Rect window, wall;
  bool median, green;
};
const RegionDefinition kIssueCandidates[] = {
    {"A: median RGB, wall (380,20) 60x60", {160, 120, 45, 45}, {380, 20, 60, 60}, true, false},
    {"B: median RGB, wall (0,360) 80x80", {160, 120, 45, 45}, {0, 360, 80, 80}, true, false},
    {"C: mean green, wall (310,40) 60x60", {160, 120, 45, 45}, {310, 40, 60, 60}, false, true},
    {"D: mean green, window (140,100) 80x80, wall (300,10) 60x60", {140, 100, 80, 80}, {300, 10, 60, 60}, false, true}};

double RegionValue(const cv::Mat& hdr, const cv::Rect& box, const RegionDefinition& d) {
  std::vector<double> v;
  for (int y = box.y; y < box.y + box.height; ++y)
    for (int x = box.x; x < box.x + box.width; ++x) {
      const cv::Vec3f p = hdr.at<cv::Vec3f>(y, x);
      v.push_back(d.green ? p[1] : (p[0] + p[1] + p[2]) / 3);
    }
  if (d.median) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  }
  double sum = 0;
  for (double x : v) sum += x;
  return sum / v.size();
}

void PrintIssueCandidates(const cv::Mat& hdr, const char* name) {
  for (const RegionDefinition& d : kIssueCandidates)
    std::cout << name << ", issue candidate " << d.name << ": "
              << RegionValue(hdr, d.window, d) / RegionValue(hdr, d.wall, d) << "\n";
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

// The bracket that exposes `region` best: the most pixels with every channel in codes 40..220.
int BestExposedBracket(const std::vector<cv::Mat>& images, const cv::Rect& region) {
  int best = 0, best_count = -1;
  for (std::size_t j = 0; j < images.size(); ++j) {
    int count = 0;
    for (int y = region.y; y < region.y + region.height; ++y)
      for (int x = region.x; x < region.x + region.width; ++x) {
        const cv::Vec3b v = images[j].at<cv::Vec3b>(y, x);
        count += v[0] >= 40 && v[0] <= 220 && v[1] >= 40 && v[1] <= 220 && v[2] >= 40 && v[2] <= 220;
      }
    if (count > best_count) best_count = count, best = static_cast<int>(j);
  }
  return best;
}

// `region` of bracket j read through `response` and divided by its time (the region's pixels
// only; the rest of the image stays 0): no weights and no black codes at all, so a check of any
// merge's ratio that only the response enters.
cv::Mat BracketRadiance(const std::vector<cv::Mat>& images, const std::vector<float>& times,
                        const cv::Mat& response, const cv::Rect& region, int j) {
  cv::Mat radiance(images[j].rows, images[j].cols, CV_32FC3, cv::Scalar::all(0));
  for (int y = region.y; y < region.y + region.height; ++y)
    for (int x = region.x; x < region.x + region.width; ++x)
      for (int c = 0; c < 3; ++c)
        radiance.at<cv::Vec3f>(y, x)[c] = response.at<cv::Vec3f>(images[j].at<cv::Vec3b>(y, x)[c])[c] / times[j];
  return radiance;
}

// Each region from the single bracket that exposes it best, under one of the issue's candidate
// definitions (mean or median, RGB mean or green): if a merge agrees with it there, the region
// definition is not why it differs from MergeDebevec.
double BestBracketValue(const std::vector<cv::Mat>& images, const std::vector<float>& times,
                        const cv::Mat& response, const cv::Rect& box, const RegionDefinition& d) {
  return RegionValue(BracketRadiance(images, times, response, box, BestExposedBracket(images, box)), box, d);
}

void PrintBestBracketCandidates(const std::vector<cv::Mat>& images, const std::vector<float>& times,
                                const cv::Mat& response, const char* name) {
  for (const RegionDefinition& d : kIssueCandidates)
    std::cout << "best single bracket per region, " << name << " response, issue candidate " << d.name << ": "
              << BestBracketValue(images, times, response, d.window, d) /
                     BestBracketValue(images, times, response, d.wall, d)
              << "\n";
}

void PrintBestBracketRatio(const std::vector<cv::Mat>& images, const std::vector<float>& times,
                           const cv::Mat& response, const char* name) {
  const int window_bracket = BestExposedBracket(images, kWindow), wall_bracket = BestExposedBracket(images, kWall);
  const cv::Mat window = BracketRadiance(images, times, response, kWindow, window_bracket);
  const cv::Mat wall = BracketRadiance(images, times, response, kWall, wall_bracket);
  std::cout << "best single bracket per region, " << name << " response: window from " << times[window_bracket]
            << " s, wall from " << times[wall_bracket] << " s: " << Ratio(window, wall) << "\n";
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
  PrintIssueCandidates(hdr, "MergeDebevec");
  cv::createCalibrateRobertson()->process(images, robertson, times);
  cv::createMergeRobertson()->process(images, hdr, times, robertson);
  std::cout << "MergeRobertson " << Ratio(hdr) << "\n";
  PrintIssueCandidates(hdr, "MergeRobertson");
  PrintBestBracketRatio(images, times, debevec, "OpenCV's Debevec");
  PrintBestBracketRatio(images, times, robertson, "OpenCV's Robertson");
  PrintBestBracketCandidates(images, times, debevec, "OpenCV's Debevec");
  PrintBestBracketCandidates(images, times, robertson, "OpenCV's Robertson");
  for (int k = 2; k < argc; ++k) {  // other merges, e.g. calibrate's hdr/cam0/00000.exr
    const cv::Mat bgr = cv::imread(argv[k], cv::IMREAD_UNCHANGED);
    if (bgr.empty() || bgr.type() != CV_32FC3) {
      std::cerr << argv[k] << ": not a 3-channel float image (set OPENCV_IO_ENABLE_OPENEXR=1)\n";
      return 1;
    }
    std::cout << argv[k] << " " << Ratio(bgr) << "\n";
    PrintIssueCandidates(bgr, argv[k]);
  }
  for (double black : {16.0, 19.0})
    std::cout << "MergeDebevec's formula, codes near black " << black << " (sigma 1.5) weighted out "
              << Ratio(MergeAboveBlack(images, times, debevec, black, 1.5)) << "\n";
}
