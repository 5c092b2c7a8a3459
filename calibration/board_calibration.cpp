#include "calibration/board_calibration.h"

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <regex>

#include "core/util/error.h"
#include "core/image/image_io.h"

namespace hdr4d {
namespace fs = std::filesystem;

BoardSpec ParseBoardSpec(const std::string& text) {
  const std::regex pattern(R"(^(\d+)x(\d+):([0-9.eE+-]+)$)");
  std::smatch m;
  BoardSpec spec;
  if (std::regex_match(text, m, pattern)) {
    spec.cols = std::stoi(m[1]);
    spec.rows = std::stoi(m[2]);
    try {
      spec.square = std::stod(m[3]);
    } catch (const std::exception&) {
      spec.square = 0;
    }
  }
  if (spec.cols < 2 || spec.rows < 2 || !(spec.square > 0))
    Fail("--board {}: expected <cols>x<rows>:<square metres> with at least 2x2 inner corners, e.g. 9x6:0.025",
         text);
  return spec;
}

BoardCalibration CalibrateFromBoard(const std::vector<fs::path>& images, const BoardSpec& board) {
  BoardCalibration result;
  std::vector<cv::Point3f> object;
  for (int r = 0; r < board.rows; ++r)
    for (int c = 0; c < board.cols; ++c)
      object.emplace_back(static_cast<float>(c * board.square), static_cast<float>(r * board.square), 0.0f);
  std::vector<std::vector<cv::Point3f>> objects;
  std::vector<std::vector<cv::Point2f>> corners;
  std::vector<std::string> names;
  cv::Size size;
  for (const fs::path& path : images) {
    const Image image = ReadImage(path);
    cv::Mat grey(image.height(), image.width(), CV_8UC1);
    for (int y = 0; y < image.height(); ++y)
      for (int x = 0; x < image.width(); ++x) {
        double sum = 0;
        for (int c = 0; c < image.channels(); ++c) sum += image.at(x, y, c);
        grey.at<uchar>(y, x) = cv::saturate_cast<uchar>(255.0 * sum / image.channels());
      }
    std::vector<cv::Point2f> found;
    if (!cv::findChessboardCorners(grey, cv::Size(board.cols, board.rows), found,
                                   cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE))
      continue;
    cv::cornerSubPix(grey, found, cv::Size(5, 5), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 1e-3));
    // OpenCV's pixel centres are at integers, ours at +0.5.
    for (cv::Point2f& p : found) p += cv::Point2f(0.5f, 0.5f);
    size = cv::Size(image.width(), image.height());
    objects.push_back(object);
    corners.push_back(found);
    names.push_back(path.filename().string());
  }
  result.views = static_cast<int>(corners.size());
  if (result.views == 0) return result;
  cv::Mat camera = (cv::Mat_<double>(3, 3) << size.width, 0, size.width / 2.0, 0, size.width, size.height / 2.0, 0, 0, 1);
  cv::Mat distortion = cv::Mat::zeros(5, 1, CV_64F);
  std::vector<cv::Mat> rvecs, tvecs;
  int flags = cv::CALIB_USE_INTRINSIC_GUESS | cv::CALIB_ZERO_TANGENT_DIST | cv::CALIB_FIX_K3 |
              cv::CALIB_FIX_ASPECT_RATIO;
  if (result.views < 3) flags |= cv::CALIB_FIX_PRINCIPAL_POINT | cv::CALIB_FIX_K2;  // too few views
  result.rms = cv::calibrateCamera(objects, corners, size, camera, distortion, rvecs, tvecs, flags);
  // The corners were shifted to our pixel convention, so the principal point is in it too.
  result.intrinsics = {camera.at<double>(0, 0), camera.at<double>(0, 2), camera.at<double>(1, 2),
                       distortion.at<double>(0), distortion.at<double>(1)};
  for (std::size_t i = 0; i < names.size(); ++i) {
    cv::Mat r;
    cv::Rodrigues(rvecs[i], r);
    Eigen::Matrix4d cam_from_board = Eigen::Matrix4d::Identity();
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) cam_from_board(a, b) = r.at<double>(a, b);
      cam_from_board(a, 3) = tvecs[i].at<double>(a);
    }
    Eigen::Matrix4d board_from_cam = Eigen::Matrix4d::Identity();
    board_from_cam.topLeftCorner<3, 3>() = cam_from_board.topLeftCorner<3, 3>().transpose();
    board_from_cam.topRightCorner<3, 1>() = -board_from_cam.topLeftCorner<3, 3>() * cam_from_board.topRightCorner<3, 1>();
    result.board_from_cam[names[i]] = board_from_cam;
  }
  return result;
}

double MetresPerUnit(const BoardCalibration& a, const BoardCalibration& b, double units) {
  if (!(units > 0)) return 0;
  double sum = 0;
  int n = 0;
  for (const auto& [name, pose_a] : a.board_from_cam) {
    const auto it = b.board_from_cam.find(name);
    if (it == b.board_from_cam.end()) continue;
    sum += (pose_a.topRightCorner<3, 1>() - it->second.topRightCorner<3, 1>()).norm();
    ++n;
  }
  return n > 0 ? sum / n / units : 0;
}

}  // namespace hdr4d
