// Restarts of the rig refinement from several focal lengths. A rig camera is seen in one pose,
// so its focal length trades against its depth along the axis, and the refinement ends (Ceres
// reports convergence) near wherever it starts (issue 54: on a distortion-free 1280x720 rig
// from 1753 to 1806 px, the least cost at 1777.9 px, the truth 1777.8). Refining from a few
// scalings of COLMAP's focal lengths and keeping the least robust cost finds the lower end.
// Deterministic: a fixed set of starts, in order.
#pragma once

#include <vector>

#include "calibration/bundle_refinement.h"

namespace hdr4d {

// 0.96 to 1.04 in steps of 0.01: the minima seen were ~1% apart, and COLMAP's focal lengths
// on the proof grid were within 2-9% of the truth.
std::vector<double> DefaultFocalStarts();

struct FocalStart {
  double scale = 1;     // of the starting focal lengths
  double focal = 0;     // the first scaled block's focal length after the refinement, px
  double cost = 0;      // the robust (Huber) cost after the refinement: the quantity Ceres minimises
  double rms = 0;       // reprojection RMS over every observation after the refinement, px
};

struct FocalStartReport {
  std::vector<FocalStart> starts;  // in the order tried
  int kept = -1;                   // index into starts: the least cost (-1: none kept)
  // Where the caller had a solution of its own to compare with (rig_geometry.cpp: the model
  // selections' refinement): its cost and first free block's focal length.
  double selection_cost = 0, selection_focal = 0;
};

// Ceres' cost of `problem` under a Huber loss of `huber_pixels`: 1/2 sum rho(|e|^2).
double RobustCost(const BundleProblem& problem, double huber_pixels);

// Every point moved to the least-squares meeting point of its rays under the problem's poses and
// intrinsics (a point with rays that do not fix it keeps its position).
void Retriangulate(BundleProblem* problem);

// For each scale: the focal lengths of `blocks` (free intrinsics blocks) multiplied by it, the
// points re-triangulated (scale 1: the problem's own points), and RefineBundle. `problem` takes
// the start of least robust cost. report->rms_before: of the problem as it came in when 1 is
// among the scales. One scale for all blocks at once: the rig cameras' errors
// from COLMAP came out alike (and the shared-focal selection that follows wants them alike).
FocalStartReport RefineFromFocalStarts(BundleProblem* problem, const std::vector<int>& blocks,
                                       const std::vector<double>& scales, const BundleOptions& options,
                                       BundleReport* report);

}  // namespace hdr4d
