#include "baselines/hexplane/app_mlp.h"

#include <gtest/gtest.h>

#include "tests/finite_difference.h"

namespace hdr4d::baselines::hexplane {
namespace {

using hdr4d::testing::FdCheck;
using hdr4d::testing::FdVector;
// Smooth away from the ReLU kinks (random inputs land on one with probability 0); step 1e-6
// leaves ~1e-9 relative error in double.
constexpr FdCheck kFd{1e-6, 1e-5};

AppMlpShape SmallShape(bool sigmoid) {
  AppMlpShape s;
  s.feature = 4;
  s.hidden = 6;
  s.sigmoid_output = sigmoid;
  return s;
}

// x = features (rows x feature) then the MLP's parameters; loss = sum up . output.
double Loss(const AppMlpShape& s, int rows, const FdVector& x) {
  const method::MlpShape layers = s.Layers();
  const double dir[3] = {0.6, -0.8, 0.0};
  RowMatrix<double> in(rows, s.Inputs());
  for (int r = 0; r < rows; ++r) EncodeInput(s, x.data() + r * s.feature, dir, in.row(r).data());
  std::vector<RowMatrix<double>> acts;
  BatchMlpForward(layers, x.data() + rows * s.feature, in, &acts);
  double l = 0;
  for (int r = 0; r < rows; ++r)
    for (int k = 0; k < 3; ++k) l += (0.5 + r - k) * acts.back()(r, k);
  return l;
}

void CheckGradients(bool sigmoid) {
  const AppMlpShape s = SmallShape(sigmoid);
  const method::MlpShape layers = s.Layers();
  constexpr int kRows = 3;
  const std::vector<float> init = InitAppMlp(s, 11);
  FdVector x(kRows * s.feature + layers.NumParams());
  for (int i = 0; i < kRows * s.feature; ++i) x(i) = 0.37 * i - 1.9;
  for (std::size_t i = 0; i < init.size(); ++i) x(kRows * s.feature + i) = init[i] + 0.05;
  const double dir[3] = {0.6, -0.8, 0.0};
  RowMatrix<double> in(kRows, s.Inputs()), up(kRows, 3), din;
  for (int r = 0; r < kRows; ++r) {
    EncodeInput(s, x.data() + r * s.feature, dir, in.row(r).data());
    for (int k = 0; k < 3; ++k) up(r, k) = 0.5 + r - k;
  }
  std::vector<RowMatrix<double>> acts;
  const double* params = x.data() + kRows * s.feature;
  BatchMlpForward(layers, params, in, &acts);
  FdVector analytic = FdVector::Zero(x.size());
  BatchMlpBackward(layers, params, in, acts, up, analytic.data() + kRows * s.feature, &din);
  for (int r = 0; r < kRows; ++r)
    EncodeInputBackward(s, x.data() + r * s.feature, din.row(r).data(),
                        analytic.data() + r * s.feature);
  kFd.ExpectMatch(analytic,
                  kFd.Gradient([&](const FdVector& v) { return Loss(s, kRows, v); }, x));
}

TEST(AppMlp, SigmoidOutputBackwardMatchesFiniteDifferences) { CheckGradients(true); }
TEST(AppMlp, LinearOutputBackwardMatchesFiniteDifferences) { CheckGradients(false); }

TEST(AppMlp, ReferenceInputWidthAndZeroLastBias) {
  const AppMlpShape s;  // the reference's: 27 + 2*2*27 + 3 + 2*2*3
  EXPECT_EQ(s.Inputs(), 150);
  const std::vector<float> p = InitAppMlp(s, 1);
  for (int k = 1; k <= 3; ++k) EXPECT_EQ(p[p.size() - k], 0.0f);
}

}  // namespace
}  // namespace hdr4d::baselines::hexplane
