// Finite-difference checks shared by every backward's test: central differences in double, a
// relative error against the largest numeric component, and a guard that the same check would
// reject a sign slip (so a check that cannot fail is caught too).
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <functional>

namespace hdr4d::testing {

using FdVector = Eigen::VectorXd;

// Central differences of f at x with step h.
inline FdVector NumericGradient(const std::function<double(const FdVector&)>& f,
                                const FdVector& x,
                                double h) {
  FdVector g(x.size());
  for (int i = 0; i < x.size(); ++i) {
    FdVector xp = x, xm = x;
    xp(i) += h;
    xm(i) -= h;
    g(i) = (f(xp) - f(xm)) / (2 * h);
  }
  return g;
}

// max |analytic - numeric| / max |numeric|.
inline double GradientError(const FdVector& analytic, const FdVector& numeric) {
  return (analytic - numeric).cwiseAbs().maxCoeff() /
         std::max(numeric.cwiseAbs().maxCoeff(), 1e-12);
}

inline void ExpectGradientsMatch(const FdVector& analytic,
                                 const FdVector& numeric,
                                 double tolerance) {
  EXPECT_LT(GradientError(analytic, numeric), tolerance)
      << "analytic " << analytic.transpose() << "\nnumeric  " << numeric.transpose();
  FdVector wrong = analytic;  // the same check must reject a sign slip in the largest component
  int i = 0;
  wrong.cwiseAbs().maxCoeff(&i);
  wrong(i) = -wrong(i);
  EXPECT_GT(GradientError(wrong, numeric), 100 * tolerance);
}

// A check with its step and tolerance, chosen per test file (each file says why):
//   constexpr FdCheck kFd{1e-5, 1e-6};  kFd.ExpectMatch(analytic, kFd.Gradient(loss, x));
struct FdCheck {
  double step;
  double tolerance;
  FdVector Gradient(const std::function<double(const FdVector&)>& f,
                    const FdVector& x,
                    double h = 0) const {
    return NumericGradient(f, x, h > 0 ? h : step);
  }
  void ExpectMatch(const FdVector& analytic, const FdVector& numeric) const {
    ExpectGradientsMatch(analytic, numeric, tolerance);
  }
};

}  // namespace hdr4d::testing
