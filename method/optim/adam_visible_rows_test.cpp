// Visible-set Adam (adam.h, "Visible rows"): a row without a gradient is skipped, and its moments
// are caught up exactly when it is seen again. Checked in double precision against dense Adam.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <sstream>
#include <vector>

#include "method/optim/adam.h"
#include "tests/testing.h"

namespace hdr4d::method {
namespace {

constexpr double kBeta1 = 0.9, kBeta2 = 0.999, kEps = 1e-15;

// Dense Adam on one element in double: the reference the float state is checked against.
struct DenseElement {
  double p, m = 0, v = 0;
  void Step(double g, double lr, int step) {
    m = kBeta1 * m + (1 - kBeta1) * g;
    v = kBeta2 * v + (1 - kBeta2) * g * g;
    const double m_hat = m / (1 - std::pow(kBeta1, step));
    const double v_hat = v / (1 - std::pow(kBeta2, step));
    p -= lr * m_hat / (std::sqrt(v_hat) + kEps);
  }
};

// Two rows of three floats: row 0 has a gradient every step, row 1 at step 1, then not for k
// steps, then again at step k + 2. Row 1's moments equal dense Adam's (in double) after the
// catch-up; its parameter equals dense Adam's minus the skipped drift, i.e. the step-1 value plus
// only the update of step k + 2. Row 0, seen every step, is dense Adam bit for bit.
TEST(AdamVisibleRows, CatchUpGivesDenseAdamsMomentsAfterKUnseenSteps) {
  for (const int k : {1, 2, 7, 100, 5000}) {  // 5000: past the tabulated powers
    const float lr = 1e-2f;
    std::vector<float> p = {0.5f, -0.25f, 1.0f, 0.3f, -0.7f, 0.1f};
    std::vector<float> p_dense = p, g(6), g_dense(6);
    Adam adam, dense;
    adam.AddGroup({"xyz", p.data(), g.data(), p.size(), lr});
    dense.AddGroup({"xyz", p_dense.data(), g_dense.data(), p_dense.size(), lr});
    adam.SetVisibleRows(true);
    std::vector<DenseElement> ref;  // row 1, dense in double
    for (int c = 0; c < 3; ++c) ref.push_back({p[3 + c]});
    std::vector<double> row1_after_step1(3);
    const auto gradient = [](int step, int c) { return 0.1 * std::sin(step * 1.3 + c) + 0.05 * c; };
    for (int step = 1; step <= k + 2; ++step) {
      const bool row1_seen = step == 1 || step == k + 2;
      for (int c = 0; c < 3; ++c) {
        g[c] = static_cast<float>(gradient(step, c));
        g[3 + c] = row1_seen ? static_cast<float>(gradient(step + 17, c)) : 0.0f;
        ref[c].Step(g[3 + c], lr, step);
      }
      g_dense = g;
      AdamRowStep visible_step = adam.BeginRowStep({"xyz"}, 2);
      visible_step.StepRows(0, 2);
      AdamRowStep dense_step = dense.BeginRowStep({"xyz"}, 2);
      dense_step.StepRows(0, 2);
      if (step == 1)
        for (int c = 0; c < 3; ++c) row1_after_step1[c] = p[3 + c];
      if (step > 1 && step < k + 2) {
        EXPECT_EQ(adam.RowStep("xyz", 1), 1);  // behind: not read nor written
        EXPECT_EQ(p[3], static_cast<float>(row1_after_step1[0]));
      }
    }
    // Row 0: every step a gradient, so exactly dense Adam.
    for (int c = 0; c < 3; ++c) EXPECT_EQ(p[c], p_dense[c]) << k;
    EXPECT_EQ(adam.RowStep("xyz", 1), k + 2);
    for (int c = 0; c < 3; ++c) {
      const double m = adam.FirstMoment("xyz")[3 + c], v = adam.SecondMoment("xyz")[3 + c];
      // Float rounding of terms near 0.1 (m can be far smaller: the gradient changes sign).
      EXPECT_NEAR(m, ref[c].m, 1e-6 * std::abs(ref[c].m) + 1e-9) << "k " << k << " c " << c;
      EXPECT_NEAR(v, ref[c].v, 1e-6 * std::abs(ref[c].v) + 1e-12) << "k " << k << " c " << c;
      // The parameter: step 1's value plus step k + 2's update from the caught-up moments.
      const int t = k + 2;
      const double m_hat = ref[c].m / (1 - std::pow(kBeta1, t));
      const double v_hat = ref[c].v / (1 - std::pow(kBeta2, t));
      const double expected = row1_after_step1[c] - lr * m_hat / (std::sqrt(v_hat) + kEps);
      EXPECT_NEAR(p[3 + c], expected, 1e-6) << "k " << k << " c " << c;
      // Dense Adam moved it further (the drift visible-set Adam skips) unless k is tiny.
      if (k >= 7) EXPECT_GT(std::abs(p_dense[3 + c] - p[3 + c]), 1e-4) << k;
    }
  }
}

// CatchUpAll brings the rows behind to dense Adam's moments; turning the mode off does too.
TEST(AdamVisibleRows, CatchUpAllDecaysTheRowsBehindOnly) {
  std::vector<float> p = {1, 2, 3, 4}, g = {0.5f, -0.5f, 0.25f, 0.125f};
  Adam adam;
  adam.AddGroup({"t", p.data(), g.data(), p.size(), 1e-3f});
  adam.SetVisibleRows(true);
  AdamRowStep first = adam.BeginRowStep({"t"}, 4);
  first.StepRows(0, 4);
  const std::vector<float> m1 = adam.FirstMoment("t"), v1 = adam.SecondMoment("t");
  g = {0.5f, 0.0f, 0.0f, 0.0f};  // rows 1..3 unseen for 3 steps
  for (int s = 0; s < 3; ++s) {
    AdamRowStep step = adam.BeginRowStep({"t"}, 4);
    step.StepRows(0, 4);
  }
  EXPECT_EQ(adam.FirstMoment("t")[2], m1[2]);
  adam.CatchUpAll();
  for (int r = 1; r < 4; ++r) {
    EXPECT_NEAR(adam.FirstMoment("t")[r], m1[r] * std::pow(kBeta1, 3), 1e-7);
    EXPECT_NEAR(adam.SecondMoment("t")[r], v1[r] * std::pow(kBeta2, 3), 1e-9);
    EXPECT_EQ(adam.RowStep("t", r), 4);
  }
  adam.SetVisibleRows(false);
  EXPECT_FALSE(adam.visible_rows());
}

// A state with rows behind is saved as version 2 with each row's step and loads to the same
// continuation; a dense state is version 1 as before.
TEST(AdamVisibleRows, SavedRowStepsResumeExactly) {
  const std::size_t rows = 50, width = 4;
  std::vector<float> g(rows * width);
  const auto steps = [&](Adam& adam, int from, int to) {
    for (int s = from; s < to; ++s) {
      for (std::size_t r = 0; r < rows; ++r)  // a third of the rows unseen at each step
        for (std::size_t c = 0; c < width; ++c)
          g[r * width + c] = (r + s) % 3 == 0 ? 0.0f : static_cast<float>(std::cos(r + c + s));
      AdamRowStep step = adam.BeginRowStep({"xyz"}, rows);
      step.StepRows(0, 20);
      step.StepRows(20, rows);
    }
  };
  std::vector<float> pa(rows * width);
  for (std::size_t i = 0; i < pa.size(); ++i) pa[i] = static_cast<float>(std::sin(0.1 * i));
  Adam a;
  a.AddGroup({"xyz", pa.data(), g.data(), pa.size(), 1e-2f});
  a.SetVisibleRows(true);
  steps(a, 0, 5);
  std::stringstream saved;
  a.Save(saved);
  EXPECT_EQ(saved.str().size(), a.SavedSize());
  EXPECT_EQ(saved.str()[8], 2);  // the version: row steps follow
  std::vector<float> pb = pa;
  Adam b;
  b.SetVisibleRows(true);
  b.Load(saved, "saved");
  b.SetBuffers("xyz", pb.data(), g.data(), pb.size());
  for (std::size_t r = 0; r < rows; ++r) EXPECT_EQ(b.RowStep("xyz", r), a.RowStep("xyz", r));
  steps(a, 5, 9);
  steps(b, 5, 9);
  EXPECT_EQ(pa, pb);
  EXPECT_EQ(a.FirstMoment("xyz"), b.FirstMoment("xyz"));
  EXPECT_EQ(a.SecondMoment("xyz"), b.SecondMoment("xyz"));
  // A dense state is written as before: version 1.
  Adam dense;
  std::vector<float> q(4), h(4, 0.5f);
  dense.AddGroup({"t", q.data(), h.data(), q.size(), 1e-3f});
  dense.Step();
  std::stringstream dense_saved;
  dense.Save(dense_saved);
  EXPECT_EQ(dense_saved.str()[8], 1);
}

}  // namespace
}  // namespace hdr4d::method
