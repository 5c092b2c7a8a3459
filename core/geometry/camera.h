// Pinhole cameras in the two axis conventions the project meets: datasets store Blender/OpenGL
// camera-to-world matrices, while projection maths and COLMAP use OpenCV axes.
//
// PIXEL CONVENTION. Pixel coordinates are continuous with the image's top-left CORNER at
// (0,0): pixel (i,j) covers [i,i+1) x [j,j+1) and its centre is at (i+0.5, j+0.5); u grows to
// the right, v grows downwards. A centred principal point is therefore cx = w/2, cy = h/2.
// This is the COLMAP and Blender convention, and it is what the 3DGS rasteriser's ndc2Pix
// computes, so a rasteriser that samples pixel centres at (i+0.5, j+0.5) agrees with Project().
//
// AXES. Camera-from-world transforms are named target_from_source.
//   GL (Blender/OpenGL, the dataset's transform_matrix): +X right, +Y up, looks down -Z.
//   CV (OpenCV/COLMAP): +X right, +Y down, looks down +Z.
// The two camera frames differ by flipping the Y and Z axes: cam_gl_from_cam_cv = diag(1,-1,-1).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products, quaternions: what camera code uses next
#include <optional>
#include <string>

namespace hdr4d {

struct PinholeIntrinsics {
  double fx = 0, fy = 0;  // focal lengths in pixels
  double cx = 0, cy = 0;  // principal point (see PIXEL CONVENTION: centred is w/2, h/2)
  int width = 0, height = 0;

  // Square pixels, centred principal point: fx = fy = 0.5 w / tan(camera_angle_x / 2).
  // Throws hdr4d::Error unless 0 < camera_angle_x < pi and the size is positive.
  static PinholeIntrinsics FromFovX(double camera_angle_x, int width, int height);

  double FovX() const;  // 2 atan(w / (2 fx)), radians
  double FovY() const;  // 2 atan(h / (2 fy))

  // Empty when valid, else what is wrong (non-positive or non-finite focal, bad size, ...).
  std::string Problem() const;
  // Throws hdr4d::Error with Problem() when invalid.
  void Validate() const;

  bool operator==(const PinholeIntrinsics&) const = default;
};

// cam_gl_from_cam_cv = diag(1,-1,-1,1); it is its own inverse, so CvFromGl() is the same matrix.
Eigen::Matrix4d GlFromCv();
Eigen::Matrix4d CvFromGl();
// world_from_cam_gl -> world_from_cam_cv and back (right-multiplication by the axis flip).
Eigen::Matrix4d WorldFromCamCvFromGl(const Eigen::Matrix4d& world_from_cam_gl);
Eigen::Matrix4d WorldFromCamGlFromCv(const Eigen::Matrix4d& world_from_cam_cv);

// Inverse of a rigid transform [R t; 0 1] as [R^T -R^T t; 0 1]: exact for rotations, and
// cheaper and better conditioned than a general inverse. The input must be rigid.
Eigen::Matrix4d RigidInverse(const Eigen::Matrix4d& target_from_source);

// Tolerance on |R^T R - I| and |det R - 1| for a pose read from a file: float32 datasets
// round their rotations at about 1e-7, anything beyond 1e-3 is scale, shear or a broken matrix.
inline constexpr double kRotationTolerance = 1e-3;

// Empty when `pose` is a rigid transform (finite, bottom row [0,0,0,1], rotation part
// orthonormal with det +1 within kRotationTolerance), else what is wrong with it.
std::string PoseProblem(const Eigen::Matrix4d& pose);

// A camera-to-world matrix in GL axes looking from `eye` at `target` with `up` roughly up.
// Requires eye != target and up not parallel to the viewing direction (checked).
Eigen::Matrix4d LookAtWorldFromCamGl(const Eigen::Vector3d& eye,
                                     const Eigen::Vector3d& target,
                                     const Eigen::Vector3d& up = Eigen::Vector3d::UnitY());

struct Camera {
  PinholeIntrinsics intrinsics;
  // The dataset's transform_matrix: camera-to-world in Blender/OpenGL axes.
  Eigen::Matrix4d world_from_cam_gl = Eigen::Matrix4d::Identity();

  static Camera FromWorldFromCamCv(const PinholeIntrinsics& intrinsics,
                                   const Eigen::Matrix4d& world_from_cam_cv);

  Eigen::Matrix4d WorldFromCamCv() const;
  Eigen::Matrix4d CamFromWorldCv() const;  // rigid inverse of WorldFromCamCv()
  Eigen::Matrix4d CamFromWorldGl() const;
  Eigen::Vector3d Center() const;         // camera centre in world coordinates
  Eigen::Vector3d ViewDirection() const;  // unit world direction the camera looks along

  // (u, v, depth): pixel coordinates (PIXEL CONVENTION above) and the depth along the viewing
  // direction (> 0). nullopt for points at or behind the camera plane (depth <= 0).
  std::optional<Eigen::Vector3d> Project(const Eigen::Vector3d& point_world) const;
  // The world point at pixel (u, v) and the given depth along the viewing direction.
  Eigen::Vector3d Unproject(double u, double v, double depth) const;

  // Throws hdr4d::Error when the intrinsics or the pose are invalid (see PoseProblem).
  void Validate() const;
};

}  // namespace hdr4d
