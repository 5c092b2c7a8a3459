#include "baselines/hexplane/hex_field.h"

#include <gtest/gtest.h>

#include "tests/finite_difference.h"

namespace hdr4d::baselines::hexplane {
namespace {

using hdr4d::testing::FdCheck;
using hdr4d::testing::FdVector;
// Products of bilinear lookups: polynomial in the values, so central differences are exact up to
// rounding.
constexpr FdCheck kFd{1e-6, 1e-6};

constexpr int kComps = 3;
const std::array<int, 3> kGrid = {3, 4, 5};
constexpr int kTimeGrid = 4;
const double kXyz[3] = {0.3, -0.45, 0.8}, kT = -0.2;

// Packs planes and basis into one vector (and back) for the finite differences.
FdVector Pack(const HexPlanes<double>& p, const std::vector<double>& basis) {
  std::vector<double> all;
  for (const Plane<double>* q : p.All()) all.insert(all.end(), q->data.begin(), q->data.end());
  all.insert(all.end(), basis.begin(), basis.end());
  return Eigen::Map<const FdVector>(all.data(), all.size());
}
void Unpack(const FdVector& x, HexPlanes<double>* p, std::vector<double>* basis) {
  int o = 0;
  for (Plane<double>* q : p->All())
    for (double& v : q->data) v = x(o++);
  for (double& v : *basis) v = x(o++);
}

TEST(HexField, DensityBackwardMatchesFiniteDifferences) {
  HexPlanes<double> planes(kComps, kGrid, kTimeGrid);
  InitPlanes(0.5, 0.1, 7, &planes);
  std::vector<double> basis(3 * kComps);
  for (int i = 0; i < 3 * kComps; ++i) basis[i] = 0.5 + 0.1 * i;
  auto loss = [&](const FdVector& x) {
    HexPlanes<double> p = planes;
    std::vector<double> b = basis;
    Unpack(x, &p, &b);
    double scratch[2 * kComps];
    return 1.7 * DensityFeature(p, b, MakePointTaps(p, kXyz, kT), scratch);
  };
  HexPlanes<double> grad(kComps, kGrid, kTimeGrid);
  std::vector<double> dbasis(3 * kComps, 0.0);
  double scratch[4 * kComps];
  DensityFeatureBackward(planes, basis, MakePointTaps(planes, kXyz, kT), 1.7, &grad, &dbasis,
                         scratch);
  kFd.ExpectMatch(Pack(grad, dbasis), kFd.Gradient(loss, Pack(planes, basis)));
}

TEST(HexField, AppearanceBackwardMatchesFiniteDifferences) {
  HexPlanes<double> planes(kComps, kGrid, kTimeGrid);
  InitPlanes(0.5, 0.1, 8, &planes);
  std::vector<double> none;
  double up[3 * kComps];
  for (int i = 0; i < 3 * kComps; ++i) up[i] = 0.3 * i - 1.0;
  auto loss = [&](const FdVector& x) {
    HexPlanes<double> p = planes;
    Unpack(x, &p, &none);
    double out[3 * kComps], scratch[kComps];
    AppProducts(p, MakePointTaps(p, kXyz, kT), out, scratch);
    double l = 0;
    for (int i = 0; i < 3 * kComps; ++i) l += up[i] * out[i];
    return l;
  };
  HexPlanes<double> grad(kComps, kGrid, kTimeGrid);
  double scratch[4 * kComps];
  AppProductsBackward(planes, MakePointTaps(planes, kXyz, kT), up, &grad, scratch);
  kFd.ExpectMatch(Pack(grad, none), kFd.Gradient(loss, Pack(planes, none)));
}

TEST(HexField, SpatialPlanesPairWithTheRemainingAxis) {
  // Only plane XY and line Z-T set: the density is their product at the point's (x, y) and (t, z).
  HexPlanes<double> planes(1, {2, 2, 2}, 2);
  std::fill(planes.space[0].data.begin(), planes.space[0].data.end(), 2.0);
  planes.time[0].data = {0.0, 0.0, 1.0, 1.0};  // height z (2) x width t (2): 0 at z=-1, 1 at z=+1
  const std::vector<double> basis(3, 1.0);
  const double xyz[3] = {0.9, -0.9, 0.5};
  double scratch[2];
  EXPECT_NEAR(DensityFeature(planes, basis, MakePointTaps(planes, xyz, 0.3), scratch),
              2.0 * 0.75, 1e-12);
}

}  // namespace
}  // namespace hdr4d::baselines::hexplane
