#include "method/optim/adam.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/util/error.h"
#include "core/util/parallel.h"
#include "method/optim/lr_schedule.h"
#include "method/raster/simd_targets_for_test.h"
#include "tests/testing.h"

namespace hdr4d::method {
namespace {

using testing::ErrorOf;

std::vector<float> RandomVector(std::size_t n, unsigned seed, float lo = -1.0f, float hi = 1.0f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(lo, hi);
  std::vector<float> v(n);
  for (float& x : v) x = u(rng);
  return v;
}

// Overwrites `dst` in place: the optimiser holds a pointer to its buffer, which a vector
// assignment from a temporary would replace.
void Fill(std::vector<float>& dst, const std::vector<float>& src) {
  ASSERT_EQ(dst.size(), src.size());
  std::copy(src.begin(), src.end(), dst.begin());
}

// torch.optim.Adam in double, written from its documented update rule.
struct ReferenceAdam {
  double beta1 = 0.9, beta2 = 0.999, eps = 1e-15;
  std::vector<double> m, v;
  int step = 0;
  void Step(std::vector<double>& p, const std::vector<float>& g, double lr) {
    m.resize(p.size(), 0.0);
    v.resize(p.size(), 0.0);
    ++step;
    for (std::size_t i = 0; i < p.size(); ++i) {
      m[i] = beta1 * m[i] + (1 - beta1) * g[i];
      v[i] = beta2 * v[i] + (1 - beta2) * double{g[i]} * g[i];
      const double m_hat = m[i] / (1 - std::pow(beta1, step));
      const double v_hat = v[i] / (1 - std::pow(beta2, step));
      p[i] -= lr * m_hat / (std::sqrt(v_hat) + eps);
    }
  }
};

TEST(Adam, FirstStepMovesByLearningRateTimesSign) {
  std::vector<float> p = RandomVector(1000, 1);
  const std::vector<float> p0 = p;
  std::vector<float> g = RandomVector(1000, 2, -3.0f, 3.0f);
  g[10] = 0.0f;  // no gradient: no move (0 / (0 + eps))
  Adam adam;
  adam.AddGroup({"xyz", p.data(), g.data(), p.size(), 0.01f});
  adam.Step();
  EXPECT_EQ(adam.StepCount("xyz"), 1);
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double expected = p0[i] - 0.01 * g[i] / (std::abs(double{g[i]}) + 1e-15);
    EXPECT_NEAR(p[i], expected, 1e-7) << i;
    EXPECT_NEAR(p[i], p0[i] - 0.01f * (g[i] > 0 ? 1 : g[i] < 0 ? -1 : 0), 1e-7) << i;
    EXPECT_FLOAT_EQ(adam.FirstMoment("xyz")[i], 0.1f * g[i]);
    EXPECT_FLOAT_EQ(adam.SecondMoment("xyz")[i], 0.001f * g[i] * g[i]);
  }
  EXPECT_EQ(p[10], p0[10]);
}

// Three hand-computed steps (bias corrections 1 - 0.9^t, 1 - 0.999^t), learning rate changed
// between steps. Golden parameters from the update rule evaluated in double.
TEST(Adam, HandComputedSteps) {
  float p = 1.0f, g = 0.0f;
  Adam adam;
  adam.AddGroup({"opacity", &p, &g, 1, 0.1f});
  g = 0.5f;
  adam.Step();
  EXPECT_NEAR(p, 0.9000000000000001, 1e-7);
  g = -0.25f;
  adam.Step();
  EXPECT_NEAR(p, 0.8733662960339601, 1e-7);
  EXPECT_NEAR(adam.FirstMoment("opacity")[0], 0.02, 1e-9);
  EXPECT_NEAR(adam.SecondMoment("opacity")[0], 0.00031225, 1e-6 * 0.00031225);
  g = 0.125f;
  adam.SetLearningRate("opacity", 0.05f);
  EXPECT_EQ(adam.LearningRate("opacity"), 0.05f);
  adam.Step();
  EXPECT_NEAR(p, 0.8563448386234996, 1e-7);
}

TEST(Adam, SeveralGroupsMatchTheReferenceOverManySteps) {
  const std::size_t n1 = 300, n2 = 77;
  std::vector<float> p1 = RandomVector(n1, 3), p2 = RandomVector(n2, 4);
  std::vector<double> r1(p1.begin(), p1.end()), r2(p2.begin(), p2.end());
  std::vector<float> g1(n1), g2(n2);
  Adam adam;
  adam.AddGroup({"a", p1.data(), g1.data(), n1, 1e-3f});
  adam.AddGroup({"b", p2.data(), g2.data(), n2, 5e-2f});
  EXPECT_EQ(adam.GroupNames(), (std::vector<std::string>{"a", "b"}));
  ReferenceAdam ref1, ref2;
  for (int step = 0; step < 50; ++step) {
    Fill(g1, RandomVector(n1, 100 + step, -2.0f, 2.0f));
    Fill(g2, RandomVector(n2, 200 + step, -1e-3f, 1e-3f));
    const float lr1 = 1e-3f * std::pow(0.9f, static_cast<float>(step));
    adam.SetLearningRate("a", lr1);
    adam.Step();
    ref1.Step(r1, g1, lr1);
    ref2.Step(r2, g2, 5e-2f);
  }
  for (std::size_t i = 0; i < n1; ++i) EXPECT_NEAR(p1[i], r1[i], 2e-6) << i;
  for (std::size_t i = 0; i < n2; ++i) EXPECT_NEAR(p2[i], r2[i], 2e-6) << i;
  EXPECT_EQ(adam.StepCount("a"), 50);
  // StepGroup advances only its group.
  adam.StepGroup("b");
  EXPECT_EQ(adam.StepCount("a"), 50);
  EXPECT_EQ(adam.StepCount("b"), 51);
}

TEST(Adam, ConvergesOnAQuadratic) {
  // f(p) = 0.5 sum c_i (p_i - t_i)^2 with curvatures over three decades.
  const std::size_t n = 64;
  const std::vector<float> target = RandomVector(n, 5, -2.0f, 2.0f);
  std::vector<float> c = RandomVector(n, 6, 0.0f, 3.0f);
  for (float& x : c) x = std::pow(10.0f, x - 2.0f);
  std::vector<float> p(n, 0.0f), g(n);
  Adam adam;
  adam.AddGroup({"x", p.data(), g.data(), n, 0.0f});
  const ExponentialLr lr{0.05, 1e-4, 3000};
  for (int step = 0; step < 3000; ++step) {
    for (std::size_t i = 0; i < n; ++i) g[i] = c[i] * (p[i] - target[i]);
    adam.SetLearningRate("x", static_cast<float>(lr(step)));
    adam.Step();
  }
  for (std::size_t i = 0; i < n; ++i) EXPECT_NEAR(p[i], target[i], 1e-3) << i;
}

TEST(Adam, ZeroLearningRateOnlyUpdatesMoments) {
  std::vector<float> p = RandomVector(10, 7), g = RandomVector(10, 8);
  const std::vector<float> p0 = p;
  Adam adam;
  adam.AddGroup({"frozen", p.data(), g.data(), p.size(), 0.0f});
  adam.Step();
  EXPECT_EQ(p, p0);
  EXPECT_FLOAT_EQ(adam.FirstMoment("frozen")[3], 0.1f * g[3]);
}

// Vectors with g = m = v = 0 are skipped by the kernel; that must be exact, and a zero gradient
// with non-zero moments must still move the parameter (momentum), as in torch.
TEST(Adam, ZeroGradientsAreExactAndMomentumStillMoves) {
  const std::size_t n = 1000;  // not a multiple of any vector width: a masked tail
  std::vector<float> p = RandomVector(n, 30), g(n, 0.0f);
  p[0] = -0.0f;
  p[n - 1] = 0.0f;
  std::vector<double> ref(p.begin(), p.end());
  // Gradients on a sparse, irregular subset only in the first step.
  std::vector<float> first(n, 0.0f);
  for (std::size_t i = 5; i < n; i += 97) first[i] = 0.5f - 0.001f * static_cast<float>(i);
  const std::vector<float> p0 = p;
  Adam adam;
  ReferenceAdam reference;
  adam.AddGroup({"f_rest", p.data(), g.data(), n, 1e-2f});
  Fill(g, first);
  adam.Step();
  reference.Step(ref, first, 1e-2);
  Fill(g, std::vector<float>(n, 0.0f));
  for (int s = 0; s < 3; ++s) {
    adam.Step();
    reference.Step(ref, g, 1e-2);
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (first[i] == 0.0f) {
      EXPECT_EQ(std::memcmp(&p[i], &p0[i], sizeof(float)), 0) << i;  // bit-identical, -0 kept
      EXPECT_EQ(adam.FirstMoment("f_rest")[i], 0.0f) << i;
      EXPECT_EQ(adam.SecondMoment("f_rest")[i], 0.0f) << i;
    } else {
      EXPECT_NEAR(p[i], ref[i], 1e-6) << i;
      EXPECT_GT(std::abs(p[i] - p0[i]), 0.02f) << i;  // beyond the first step's lr = 0.01
    }
  }
}

TEST(Adam, EmptyGroupsAreAllowed) {
  Adam adam;
  adam.AddGroup({"none", nullptr, nullptr, 0, 1e-3f});
  adam.Step();
  EXPECT_EQ(adam.StepCount("none"), 1);
  adam.AppendRows("none", 2, 3);
  EXPECT_EQ(adam.group("none").size, 6u);
  std::vector<float> p(6, 1.0f), g(6, 1.0f);
  adam.SetBuffers("none", p.data(), g.data(), 6);
  adam.Step();
  // The group is at step 2, so new entries get step-2 bias corrections (as in torch, whose step
  // count is per tensor): their first move is lr (0.1 / 0.19) / sqrt(0.001 / 0.001999) < lr.
  EXPECT_NEAR(p[0], 1.0 - 1e-3 * (0.1 / 0.19) / std::sqrt(0.001 / 0.001999), 1e-7);
}

// Rows kept by GatherGroup continue exactly as an optimiser that only ever saw those rows.
void ExpectGatherKeepsMomentsAlignedWithRows(const std::vector<std::uint32_t>& keep) {
  constexpr std::size_t kWidth = 3, kRows = 6;
  std::vector<float> p = RandomVector(kRows * kWidth, 9), g(kRows * kWidth);
  std::vector<float> q, h(keep.size() * kWidth);  // the kept rows only, from the start
  for (std::uint32_t r : keep)
    q.insert(q.end(), p.begin() + r * kWidth, p.begin() + (r + 1) * kWidth);
  Adam full, kept;
  full.AddGroup({"rot", p.data(), g.data(), p.size(), 1e-2f});
  kept.AddGroup({"rot", q.data(), h.data(), q.size(), 1e-2f});
  auto gradients = [&](int step, std::size_t rows, const std::vector<std::uint32_t>* map) {
    std::vector<float> out(rows * kWidth);
    const std::vector<float> all = RandomVector(kRows * kWidth, 300 + step);
    for (std::size_t k = 0; k < rows; ++k) {
      const std::size_t from = map ? (*map)[k] : k;
      for (std::size_t c = 0; c < kWidth; ++c) out[k * kWidth + c] = all[from * kWidth + c];
    }
    return out;
  };
  for (int step = 0; step < 4; ++step) {
    Fill(g, gradients(step, kRows, nullptr));
    Fill(h, gradients(step, keep.size(), &keep));
    full.Step();
    kept.Step();
  }
  // The same surgery on the parameters and on the optimiser.
  std::vector<float> gathered;
  for (std::uint32_t r : keep) {
    gathered.insert(gathered.end(), p.begin() + r * kWidth, p.begin() + (r + 1) * kWidth);
  }
  p = gathered;
  g.assign(p.size(), 0.0f);
  full.GatherGroup("rot", keep, kWidth);
  EXPECT_EQ(full.group("rot").params, nullptr);  // unbound until SetBuffers
  EXPECT_EQ(full.group("rot").size, keep.size() * kWidth);
  full.SetBuffers("rot", p.data(), g.data(), p.size());
  EXPECT_EQ(full.FirstMoment("rot"), kept.FirstMoment("rot"));
  EXPECT_EQ(full.SecondMoment("rot"), kept.SecondMoment("rot"));
  EXPECT_EQ(full.StepCount("rot"), 4);
  for (int step = 4; step < 8; ++step) {
    // Both see the kept rows' gradients, laid out in the kept order.
    Fill(h, gradients(step, keep.size(), &keep));
    Fill(g, h);
    full.Step();
    kept.Step();
  }
  EXPECT_EQ(p, q);  // bit-identical: the same float operations on the same values
}

TEST(Adam, GatherKeepsMomentsAlignedWithRows) {
  ExpectGatherKeepsMomentsAlignedWithRows({5, 0, 2});     // any order: new buffers
  ExpectGatherKeepsMomentsAlignedWithRows({1, 2, 4, 5});  // increasing, as densification keeps
  ExpectGatherKeepsMomentsAlignedWithRows({0, 1, 2});     // the first rows: nothing moves
}

// Appended rows start with zero moments; the old rows are unaffected.
TEST(Adam, AppendRowsStartWithZeroMoments) {
  constexpr std::size_t kWidth = 4;
  std::vector<float> p = RandomVector(2 * kWidth, 10), g = RandomVector(2 * kWidth, 11);
  std::vector<float> q = p, h = g;
  Adam grown, plain;
  grown.AddGroup({"xyz", p.data(), g.data(), p.size(), 1e-3f});
  plain.AddGroup({"xyz", q.data(), h.data(), q.size(), 1e-3f});
  grown.Step();
  plain.Step();
  // Densification appends a clone of row 1.
  p.insert(p.end(), p.begin() + kWidth, p.begin() + 2 * kWidth);
  g.resize(p.size());
  grown.AppendRows("xyz", 1, kWidth);
  grown.SetBuffers("xyz", p.data(), g.data(), p.size());
  for (std::size_t i = 2 * kWidth; i < 3 * kWidth; ++i) {
    EXPECT_EQ(grown.FirstMoment("xyz")[i], 0.0f);
    EXPECT_EQ(grown.SecondMoment("xyz")[i], 0.0f);
  }
  const std::vector<float> next = RandomVector(3 * kWidth, 12);
  std::copy(next.begin(), next.end(), g.begin());
  std::copy(next.begin(), next.begin() + 2 * kWidth, h.begin());
  const std::vector<float> before = p;
  grown.Step();
  plain.Step();
  for (std::size_t i = 0; i < 2 * kWidth; ++i) EXPECT_EQ(p[i], q[i]) << i;
  // A new row at the group's step 2: m = 0.1 g, v = 0.001 g^2, bias-corrected with step 2.
  for (std::size_t i = 2 * kWidth; i < 3 * kWidth; ++i) {
    const double gi = next[i];
    EXPECT_FLOAT_EQ(grown.FirstMoment("xyz")[i], static_cast<float>(0.1 * gi));
    EXPECT_NEAR(grown.SecondMoment("xyz")[i], 0.001 * gi * gi, 1e-9);
    const double m_hat = 0.1 * gi / (1 - 0.81);
    const double v_hat = 0.001 * gi * gi / (1 - 0.998001);
    EXPECT_NEAR(p[i], before[i] - 1e-3 * m_hat / (std::sqrt(v_hat) + 1e-15), 1e-7) << i;
  }
}

TEST(Adam, ResizeAndResetMoments) {
  std::vector<float> p = RandomVector(12, 13), g = RandomVector(12, 14);
  Adam adam;
  adam.AddGroup({"scaling", p.data(), g.data(), 12, 1e-3f});
  adam.Step();
  const std::vector<float> m = adam.FirstMoment("scaling");
  adam.ResizeGroup("scaling", 8);
  EXPECT_EQ(adam.FirstMoment("scaling"), std::vector<float>(m.begin(), m.begin() + 8));
  adam.ResizeGroup("scaling", 10);
  EXPECT_EQ(adam.FirstMoment("scaling")[9], 0.0f);
  EXPECT_EQ(adam.FirstMoment("scaling")[7], m[7]);
  EXPECT_EQ(adam.StepCount("scaling"), 1);
  // Rows of width 2: reset rows 1 and 3 only.
  adam.ResetMoments("scaling", {1, 3}, 2);
  for (std::size_t i : {2u, 3u, 6u, 7u}) {
    EXPECT_EQ(adam.FirstMoment("scaling")[i], 0.0f) << i;
    EXPECT_EQ(adam.SecondMoment("scaling")[i], 0.0f) << i;
  }
  EXPECT_EQ(adam.FirstMoment("scaling")[4], m[4]);
  EXPECT_NE(adam.SecondMoment("scaling")[5], 0.0f);
  adam.ResetMoments("scaling");
  EXPECT_EQ(adam.FirstMoment("scaling"), std::vector<float>(10, 0.0f));
  EXPECT_EQ(adam.SecondMoment("scaling"), std::vector<float>(10, 0.0f));
  EXPECT_EQ(adam.StepCount("scaling"), 1);  // as torch's opacity reset: the step stays
}

TEST(Adam, BitIdenticalAtAnyThreadCount) {
  const std::size_t n = 200000;
  auto run = [&](int threads) {
    ThreadLimit limit(threads);
    std::vector<float> p = RandomVector(n, 15), g(n);
    Adam adam;
    adam.AddGroup({"f_rest", p.data(), g.data(), n, 1e-3f});
    for (int s = 0; s < 3; ++s) {
      Fill(g, RandomVector(n, 16 + s));
      adam.Step();
    }
    return p;
  };
  const std::vector<float> one = run(1);
  EXPECT_TRUE(run(2) == one);
  EXPECT_TRUE(run(0) == one);
}

// On every compiled target (AVX-512, AVX2, SSE4, SSSE3, scalar), over gradients from 1e-22 to 1e14
// (v from denormal to 1e25, where eps dominates and where it vanishes, mixed within vectors, and a
// masked tail): each step is within a few ulps of torch's formula in double on the same moments.
TEST(Adam, EveryTargetStepsWithinUlpsOfTheExactFormula) {
  const std::size_t n = 4099;  // a masked tail on every target
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> exponent(-22.0, 14.0);
  std::vector<std::vector<float>> grads(3, std::vector<float>(n));
  for (auto& g : grads)
    for (float& x : g) x = static_cast<float>((rng() & 1 ? 1 : -1) * std::pow(10.0, exponent(rng)));
  const std::vector<float> p0 = RandomVector(n, 22);
  const int ran = ForEachCompiledTarget([&] {
    std::vector<float> p = p0, g(n);
    Adam adam;  // eps 1e-15, as the reference's
    adam.AddGroup({"f_rest", p.data(), g.data(), n, 1e-3f});
    for (int step = 1; step <= 3; ++step) {
      const std::vector<float> before = p;
      Fill(g, grads[step - 1]);
      adam.Step();
      const double bias1 = 1.0 - std::pow(0.9, step), bias2 = 1.0 - std::pow(0.999, step);
      for (std::size_t i = 0; i < n; ++i) {
        const double m = adam.FirstMoment("f_rest")[i], v = adam.SecondMoment("f_rest")[i];
        const double want = 1e-3 / bias1 * m / (std::sqrt(v / bias2) + 1e-15);
        const double got = static_cast<double>(before[i]) - p[i];
        // 8 ulps of the step, plus the rounding of p itself.
        ASSERT_LE(std::abs(got - want), 1e-6 * std::abs(want) + 6e-8 * std::abs(before[i]))
            << "step " << step << " value " << i << " g " << g[i] << " v " << v;
      }
    }
  });
  EXPECT_GE(ran, 1);
}

// ---- Checkpoints
// ---------------------------------------------------------------------------------

struct Fixture {
  std::vector<float> p1 = RandomVector(40, 17), g1 = RandomVector(40, 18);
  std::vector<float> p2 = RandomVector(7, 19), g2 = RandomVector(7, 20);
  Adam adam{AdamOptions{0.8, 0.99, 1e-12}};
  Fixture() {
    adam.AddGroup({"xyz", p1.data(), g1.data(), p1.size(), 1e-3f});
    adam.AddGroup({"tone_mapper", p2.data(), g2.data(), p2.size(), 5e-4f});
    for (int s = 0; s < 3; ++s) adam.Step();
    adam.StepGroup("xyz");
  }
  std::string Saved() const {
    std::ostringstream out;
    adam.Save(out);
    return out.str();
  }
};

// A checkpoint writes SavedSize() as the state's length before streaming Save into the file.
TEST(AdamState, SavedSizeIsTheLengthSaveWrites) {
  EXPECT_EQ(Adam().SavedSize(), [] {
    std::ostringstream out;
    Adam().Save(out);
    return out.str().size();
  }());
  Fixture a;
  EXPECT_EQ(a.adam.SavedSize(), a.Saved().size());
  a.adam.AppendRows("xyz", 3, 4);  // sizes change with densification
  EXPECT_EQ(a.adam.SavedSize(), a.Saved().size());
}

TEST(AdamState, SaveLoadRoundTripThenIdenticalSteps) {
  Fixture a;
  const std::string bytes = a.Saved();
  Adam b;  // different options and no groups: Load replaces everything
  std::istringstream in(bytes);
  b.Load(in, "state.bin");
  EXPECT_EQ(b.options().beta1, 0.8);
  EXPECT_EQ(b.options().beta2, 0.99);
  EXPECT_EQ(b.options().eps, 1e-12);
  EXPECT_EQ(b.GroupNames(), (std::vector<std::string>{"xyz", "tone_mapper"}));
  EXPECT_EQ(b.StepCount("xyz"), 4);
  EXPECT_EQ(b.StepCount("tone_mapper"), 3);
  EXPECT_EQ(b.LearningRate("tone_mapper"), 5e-4f);
  EXPECT_EQ(b.group("xyz").params, nullptr);  // unbound: b had no such group
  {
    std::ostringstream again;
    b.Save(again);
    EXPECT_EQ(again.str(), bytes);  // exact round trip
  }
  std::vector<float> q1 = a.p1, q2 = a.p2, h1 = a.g1, h2 = a.g2;
  b.SetBuffers("xyz", q1.data(), h1.data(), q1.size());
  b.SetBuffers("tone_mapper", q2.data(), h2.data(), q2.size());
  for (int s = 0; s < 3; ++s) {
    Fill(a.g1, RandomVector(40, 40 + s));
    Fill(a.g2, RandomVector(7, 50 + s));
    Fill(h1, a.g1);
    Fill(h2, a.g2);
    a.adam.Step();
    b.Step();
  }
  EXPECT_EQ(a.p1, q1);
  EXPECT_EQ(a.p2, q2);
}

TEST(AdamState, LoadKeepsBuffersOfMatchingGroups) {
  Fixture a;
  const std::string bytes = a.Saved();
  std::vector<float> p(40), g(40), small(3), small_g(3);
  Adam b;
  b.AddGroup({"xyz", p.data(), g.data(), 40, 0.0f});
  b.AddGroup({"tone_mapper", small.data(), small_g.data(), 3, 0.0f});
  std::istringstream in(bytes);
  b.Load(in, "state.bin");
  EXPECT_EQ(b.group("xyz").params, p.data());
  EXPECT_EQ(b.group("xyz").grads, g.data());
  EXPECT_EQ(b.group("tone_mapper").params, nullptr);  // size changed 3 -> 7
  EXPECT_EQ(b.LearningRate("xyz"), 1e-3f);
}

// Every strict prefix of a valid state is reported as truncated, and the optimiser is unchanged.
TEST(AdamState, TruncatedStreamsAreErrors) {
  Fixture a;
  const std::string bytes = a.Saved();
  Fixture b;
  for (std::size_t len = 0; len < bytes.size(); ++len) {
    std::istringstream in(bytes.substr(0, len));
    const std::string message = ErrorOf([&] { b.adam.Load(in, "cut.bin"); });
    ASSERT_NE(message.find("cut.bin: Adam state is truncated while reading"), std::string::npos)
        << len << ": " << message;
  }
  EXPECT_EQ(ErrorOf([&] {
              std::istringstream in("");
              b.adam.Load(in, "empty.bin");
            }),
            "empty.bin: Adam state is truncated while reading the header");
  EXPECT_EQ(b.adam.StepCount("xyz"), 4);
  EXPECT_EQ(b.adam.options().beta1, 0.8);
}

TEST(AdamState, CorruptHeaderAndDataAreErrors) {
  Fixture a;
  const std::string bytes = a.Saved();
  auto load = [](const std::string& data) {
    Adam b;
    std::istringstream in(data);
    return ErrorOf([&] { b.Load(in, "opt.bin"); });
  };
  EXPECT_EQ(load(bytes), "");
  std::string bad = bytes;
  bad[0] = 'X';
  EXPECT_EQ(load(bad), "opt.bin: not an Adam optimiser state (bad magic; expected \"HDR4DADM\")");
  bad = bytes;
  bad[8] = 3;
  EXPECT_EQ(load(bad),
            "opt.bin: Adam state version 3 is not supported (this build reads versions 1 and 2)");
  // A version-1 state read as version 2 (visible rows' row steps) runs out of bytes or is
  // refused: never read as something else.
  bad = bytes;
  bad[8] = 2;
  EXPECT_NE(load(bad).find("opt.bin: "), std::string::npos);
  // A flipped bit in a moment, in the learning rate, in a step count: the checksum sees it.
  for (std::size_t at : {bytes.size() - 20, bytes.size() / 2, std::size_t{60}}) {
    bad = bytes;
    bad[at] ^= 0x10;
    const std::string message = load(bad);
    EXPECT_NE(message.find("opt.bin: Adam state"), std::string::npos) << at;
    EXPECT_FALSE(message.empty()) << at;
  }
  bad = bytes;
  bad[bytes.size() - 20] ^= 0x10;
  EXPECT_NE(load(bad).find("checksum mismatch"), std::string::npos);
}

// Streams built by hand in the documented format, with a valid checksum, so the value checks
// behind the checksum are reached.
class StateBuilder {
 public:
  StateBuilder(double beta1 = 0.9,
               double beta2 = 0.999,
               double eps = 1e-15,
               std::uint32_t groups = 1) {
    bytes_.append("HDR4DADM");
    Raw(std::uint32_t{1});
    hashed_from_ = bytes_.size();
    Raw(beta1);
    Raw(beta2);
    Raw(eps);
    Raw(groups);
  }
  StateBuilder& Group(const std::string& name,
                      std::int64_t step,
                      float lr,
                      const std::vector<float>& m,
                      const std::vector<float>& v,
                      std::uint64_t size_override = 0) {
    Raw(static_cast<std::uint32_t>(name.size()));
    bytes_.append(name);
    Raw(size_override ? size_override : static_cast<std::uint64_t>(m.size()));
    Raw(step);
    Raw(lr);
    for (float x : m) Raw(x);
    for (float x : v) Raw(x);
    return *this;
  }
  std::string Finish() const {
    std::uint64_t hash = 14695981039346656037ull;
    for (std::size_t i = hashed_from_; i < bytes_.size(); ++i) {
      hash = (hash ^ static_cast<unsigned char>(bytes_[i])) * 1099511628211ull;
    }
    std::string out = bytes_;
    out.append(reinterpret_cast<const char*>(&hash), sizeof(hash));
    return out;
  }

 private:
  template <typename T>
  void Raw(T value) {
    bytes_.append(reinterpret_cast<const char*>(&value), sizeof(T));
  }
  std::string bytes_;
  std::size_t hashed_from_ = 0;
};

TEST(AdamState, HandBuiltStreamMatchesTheDocumentedFormat) {
  float p = 1.0f, g = 0.5f;
  Adam a;
  a.AddGroup({"t", &p, &g, 1, 0.25f});
  a.Step();
  std::ostringstream out;
  a.Save(out);
  const std::string built =
      StateBuilder().Group("t", 1, 0.25f, {0.1f * 0.5f}, {0.001f * 0.5f * 0.5f}).Finish();
  EXPECT_EQ(out.str(), built);
}

TEST(AdamState, InvalidValuesBehindAValidChecksumAreErrors) {
  auto load = [](const std::string& data) {
    Adam b;
    std::istringstream in(data);
    return ErrorOf([&] { b.Load(in, "opt.bin"); });
  };
  const std::vector<float> one = {0.5f};
  EXPECT_EQ(load(StateBuilder().Group("xyz", 1, 1e-3f, one, one).Finish()), "");
  EXPECT_EQ(load(StateBuilder(1.0).Group("xyz", 1, 1e-3f, one, one).Finish()),
            "opt.bin: Adam state has invalid options: beta1 must be in [0, 1), got 1");
  EXPECT_EQ(load(StateBuilder().Group("xyz", -2, 1e-3f, one, one).Finish()),
            "opt.bin: Adam state group 'xyz' has a negative step count -2");
  EXPECT_EQ(load(StateBuilder().Group("xyz", 1, -1.0f, one, one).Finish()),
            "opt.bin: Adam state group 'xyz' has an invalid learning rate -1");
  EXPECT_EQ(load(StateBuilder().Group("xyz", 1, 1e-3f, {0.0f, 0.0f}, {0.0f, -1.0f}).Finish()),
            "opt.bin: Adam state group 'xyz' has an invalid moment at index 1 (m = 0, v = -1)");
  EXPECT_EQ(load(StateBuilder().Group("xyz", 1, 1e-3f, {NAN}, one).Finish()),
            "opt.bin: Adam state group 'xyz' has an invalid moment at index 0 (m = nan, v = 0.5)");
  EXPECT_EQ(load(StateBuilder(0.9, 0.999, 1e-15, 2)
                     .Group("xyz", 1, 1e-3f, one, one)
                     .Group("xyz", 1, 1e-3f, one, one)
                     .Finish()),
            "opt.bin: Adam state has two groups named 'xyz'");
  EXPECT_EQ(load(StateBuilder().Group("", 1, 1e-3f, one, one).Finish()),
            "opt.bin: Adam state group 0 has a name of length 0 (must be 1..4096: corrupt)");
  EXPECT_EQ(load(StateBuilder().Group("xyz", 1, 1e-3f, one, one, std::uint64_t{1} << 50).Finish()),
            "opt.bin: Adam state group 'xyz' claims 1125899906842624 values (corrupt)");
  EXPECT_EQ(load(StateBuilder(0.9, 0.999, 1e-15, 1u << 20).Finish()),
            "opt.bin: Adam state claims 1048576 parameter groups (more than 65536: corrupt)");
  // A huge but allowed size on a short stream fails as truncated without allocating it all.
  EXPECT_EQ(load(StateBuilder().Group("xyz", 1, 1e-3f, one, one, std::uint64_t{1} << 39).Finish()),
            "opt.bin: Adam state is truncated while reading group 'xyz' first moments");
}

// ---- Options and helpers
// -------------------------------------------------------------------------

TEST(AdamOptions, ValidateAndConstructor) {
  EXPECT_EQ(AdamOptions{}.Validate(), "");
  EXPECT_EQ(AdamOptions{}.eps, 1e-15);
  EXPECT_EQ((AdamOptions{-0.1}.Validate()), "beta1 must be in [0, 1), got -0.1");
  EXPECT_EQ((AdamOptions{0.9, 1.0}.Validate()), "beta2 must be in [0, 1), got 1");
  EXPECT_EQ((AdamOptions{0.9, 0.999, 0.0}.Validate()), "eps must be positive and finite, got 0");
  EXPECT_EQ((AdamOptions{0.9, 0.999, INFINITY}.Validate()),
            "eps must be positive and finite, got inf");
  EXPECT_EQ(ErrorOf([] {
              Adam adam(AdamOptions{0.9, NAN});
            }),
            "Adam options: beta2 must be in [0, 1), got nan");
}

TEST(AllFinite, FindsNanAndInfinityAnywhere) {
  EXPECT_TRUE(AllFinite(nullptr, 0));
  for (std::size_t n : {std::size_t{1}, std::size_t{17}, std::size_t{300000}}) {
    std::vector<float> v = RandomVector(n, 21, -1e30f, 1e30f);
    v[0] = std::numeric_limits<float>::max();
    v[n - 1] = -std::numeric_limits<float>::denorm_min();
    EXPECT_TRUE(AllFinite(v.data(), n)) << n;
    for (float bad : {NAN, INFINITY, -INFINITY}) {
      for (std::size_t at : {std::size_t{0}, n / 2, n - 1}) {
        std::vector<float> w = v;
        w[at] = bad;
        EXPECT_FALSE(AllFinite(w.data(), n)) << n << " " << at << " " << bad;
      }
    }
  }
}

TEST(Adam, FirstNonFiniteGradientNamesTheGroup) {
  std::vector<float> p(5), g(5, 1.0f), q(300000), h(300000, 0.5f);
  Adam adam;
  adam.AddGroup({"xyz", p.data(), g.data(), 5, 1e-3f});
  adam.AddGroup({"f_rest", q.data(), h.data(), q.size(), 1e-3f});
  EXPECT_EQ(adam.FirstNonFiniteGradient(), "");
  h[123456] = NAN;
  EXPECT_EQ(adam.FirstNonFiniteGradient(), "f_rest");
  g[4] = -INFINITY;
  EXPECT_EQ(adam.FirstNonFiniteGradient(), "xyz");
}

TEST(Adam, FirstNonFiniteGradientOfChosenGroups) {
  std::vector<float> p(5), g(5, 1.0f), q(7), h(7, NAN);
  Adam adam;
  adam.AddGroup({"xyz", p.data(), g.data(), 5, 1e-3f});
  adam.AddGroup({"f_rest", q.data(), h.data(), 7, 1e-3f});
  EXPECT_EQ(adam.FirstNonFiniteGradient({"xyz"}), "");
  EXPECT_EQ(adam.FirstNonFiniteGradient({"f_rest"}), "f_rest");
  EXPECT_EQ(adam.FirstNonFiniteGradient({}), "");
}

// The fused row step (rows in uneven blocks, in any order, from several threads) gives exactly
// the values of StepGroup, and counts one step per group.
TEST(AdamRowStep, EqualsStepGroupBitForBit) {
  const std::size_t rows = 1000;
  const std::vector<std::size_t> widths = {3, 1, 141, 4};
  auto run = [&](bool fused) {
    std::vector<std::vector<float>> p, g;
    for (std::size_t k = 0; k < widths.size(); ++k) {
      p.push_back(RandomVector(rows * widths[k], 30 + static_cast<unsigned>(k)));
      g.emplace_back(rows * widths[k]);
    }
    Adam adam;
    std::vector<std::string> names;
    for (std::size_t k = 0; k < widths.size(); ++k) {
      names.push_back("group" + std::to_string(k));
      adam.AddGroup({names.back(), p[k].data(), g[k].data(), p[k].size(), 1e-3f * (k + 1)});
    }
    for (int s = 0; s < 4; ++s) {
      for (std::size_t k = 0; k < widths.size(); ++k) {
        Fill(g[k], RandomVector(g[k].size(), 40 + s * 10 + static_cast<unsigned>(k), -2, 2));
        std::fill_n(g[k].begin(), std::min<std::size_t>(g[k].size(), 40), 0.0f);  // zero rows
      }
      if (!fused) {
        adam.Step();
        continue;
      }
      AdamRowStep step = adam.BeginRowStep(names, rows);
      // Blocks of 1..97 rows, stepped from the end backwards, in parallel.
      std::vector<std::pair<std::int64_t, std::int64_t>> blocks;
      for (std::int64_t b = 0; b < static_cast<std::int64_t>(rows);) {
        const std::int64_t e = std::min<std::int64_t>(rows, b + 1 + (b * 7919) % 97);
        blocks.emplace_back(b, e);
        b = e;
      }
      std::reverse(blocks.begin(), blocks.end());
      ParallelFor(static_cast<std::int64_t>(blocks.size()), 1,
                  [&](std::int64_t i) { step.StepRows(blocks[i].first, blocks[i].second); });
      EXPECT_EQ(step.FirstNonFinite(), "");
    }
    for (const std::string& name : names) EXPECT_EQ(adam.StepCount(name), 4);
    return p;
  };
  EXPECT_TRUE(run(true) == run(false));
}

// Columns that have never had a gradient (zero gradient, zero moments) may be left out of a
// row step: the result equals stepping them, bit for bit, including with -0 gradients (a zero
// weight times a negative colour gradient) and as the stepped columns grow like the colour
// degrees. Leaving out a column that does have a gradient is seen (the test can fail).
TEST(AdamRowStep, LimitColumnsSkipsOnlyWhatAFullStepLeavesAlone) {
  const std::size_t rows = 300, width = 45;
  const auto run = [&](bool limit, bool wrong) {
    std::vector<float> p = RandomVector(rows * width, 70), g(rows * width, 0.0f);
    std::vector<float> other = RandomVector(rows * 3, 71), other_g(rows * 3);
    Adam adam;
    adam.AddGroup({"f_rest", p.data(), g.data(), p.size(), 1e-3f});
    adam.AddGroup({"xyz", other.data(), other_g.data(), other.size(), 1e-2f});
    for (int s = 0; s < 6; ++s) {
      const std::size_t active = std::min<std::size_t>(width, 9 * (s / 2));  // 0, 0, 9, 9, 18..
      const std::vector<float> r = RandomVector(g.size(), 80 + s, -2, 2);
      for (std::size_t row = 0; row < rows; ++row)
        for (std::size_t c = 0; c < width; ++c)
          g[row * width + c] = c < active ? r[row * width + c] : (c % 2 ? -0.0f : 0.0f);
      if (wrong) g[5 * width + active] = 0.5f;  // a gradient in a skipped column
      Fill(other_g, RandomVector(other_g.size(), 90 + s, -2, 2));
      AdamRowStep step = adam.BeginRowStep({"xyz", "f_rest"}, rows);
      if (limit) step.LimitColumns("f_rest", active);
      step.StepRows(0, 123);
      step.StepRows(123, rows);
      EXPECT_EQ(step.FirstNonFinite(), "");
    }
    std::vector<float> all = p;
    all.insert(all.end(), other.begin(), other.end());
    all.insert(all.end(), adam.FirstMoment("f_rest").begin(), adam.FirstMoment("f_rest").end());
    all.insert(all.end(), adam.SecondMoment("f_rest").begin(), adam.SecondMoment("f_rest").end());
    return all;
  };
  const std::vector<float> full = run(false, false);
  const std::vector<float> limited = run(true, false);
  ASSERT_EQ(full.size(), limited.size());
  EXPECT_EQ(std::memcmp(full.data(), limited.data(), full.size() * sizeof(float)), 0);
  EXPECT_NE(run(false, true), run(true, true));
}

TEST(AdamRowStep, NamesTheFirstNonFiniteGroupAndLeavesItsVectorAlone) {
  const std::size_t rows = 64;
  std::vector<float> p1 = RandomVector(rows * 3, 50), g1 = RandomVector(rows * 3, 51);
  std::vector<float> p2 = RandomVector(rows * 2, 52), g2 = RandomVector(rows * 2, 53);
  Adam adam;
  adam.AddGroup({"xyz", p1.data(), g1.data(), p1.size(), 1e-2f});
  adam.AddGroup({"t", p2.data(), g2.data(), p2.size(), 1e-2f});
  g2[101] = NAN;
  g1[5] = INFINITY;
  const std::vector<float> p1_before = p1, p2_before = p2;
  {
    AdamRowStep step = adam.BeginRowStep({"t", "xyz"}, rows);
    step.StepRows(0, rows);
    EXPECT_EQ(step.FirstNonFinite(), "t");  // in the order given
  }
  // The update skips whole vectors around a bad value (16 floats with AVX-512, fewer on other
  // targets, whole masked tails): the bad element itself and its moments never change, and no
  // NaN reaches any parameter or moment.
  EXPECT_EQ(p2[101], p2_before[101]);
  EXPECT_EQ(p1[5], p1_before[5]);
  EXPECT_EQ(adam.FirstMoment("t")[101], 0.0f);
  EXPECT_EQ(adam.SecondMoment("xyz")[5], 0.0f);
  EXPECT_TRUE(AllFinite(p1.data(), p1.size()) && AllFinite(p2.data(), p2.size()));
  EXPECT_TRUE(AllFinite(adam.FirstMoment("t").data(), p2.size()));
  EXPECT_NE(p1.back(), p1_before.back());  // elements far from the bad one did step
  {
    AdamRowStep step = adam.BeginRowStep({"xyz"}, rows);
    step.StepRows(0, 10);
    EXPECT_EQ(step.FirstNonFinite(), "xyz");
  }
  g1[5] = 0.0f;
  g2[101] = 0.0f;
  AdamRowStep step = adam.BeginRowStep({"xyz", "t"}, rows);
  step.StepRows(0, rows);
  EXPECT_EQ(step.FirstNonFinite(), "");
}

TEST(AdamDeathTest, CallerBugsAbort) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  std::vector<float> p(6), g(6);
  Adam adam;
  adam.AddGroup({"xyz", p.data(), g.data(), 6, 1e-3f});
  EXPECT_DEATH(adam.AddGroup({"xyz", p.data(), g.data(), 6, 1e-3f}), "internal check failed");
  EXPECT_DEATH(adam.StepGroup("nope"), "no parameter group 'nope'");
  EXPECT_DEATH(adam.SetBuffers("xyz", p.data(), g.data(), 5), "internal check failed");
  EXPECT_DEATH(adam.GatherGroup("xyz", {0, 2}, 3), "internal check failed");  // row 2 of 2
  EXPECT_DEATH(adam.GatherGroup("xyz", {0}, 4), "internal check failed");     // 6 % 4 != 0
  EXPECT_DEATH(adam.ResetMoments("xyz", {5}, 2), "internal check failed");
  adam.AppendRows("xyz", 1, 3);
  EXPECT_DEATH(adam.Step(), "internal check failed");  // unbound after surgery
}

}  // namespace
}  // namespace hdr4d::method
