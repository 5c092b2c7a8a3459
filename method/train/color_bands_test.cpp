#include "method/train/color_bands.h"

#include <gtest/gtest.h>

#include <random>

#include "core/util/error.h"

namespace hdr4d::method {
namespace {

const ColorBasis kBasis{.max_sh_degree = 3, .max_time_degree = 2};

TEST(ColorBands, ScheduleIsTheReferencesSpatialThenTemporal) {
  EXPECT_EQ(ScheduledDegrees(999, kBasis, true, 1000), (BandDegrees{0, 0}));
  EXPECT_EQ(ScheduledDegrees(1000, kBasis, true, 1000), (BandDegrees{1, 0}));
  EXPECT_EQ(ScheduledDegrees(3000, kBasis, true, 1000), (BandDegrees{3, 0}));
  EXPECT_EQ(ScheduledDegrees(4000, kBasis, true, 1000), (BandDegrees{3, 1}));
  EXPECT_EQ(ScheduledDegrees(90000, kBasis, true, 1000), (BandDegrees{3, 2}));
  EXPECT_EQ(ScheduledDegrees(90000, kBasis, false, 1000), (BandDegrees{3, 0}));
}

TEST(ColorBands, NextBandAndItsColumnsAreTheTailOfTheRow) {
  EXPECT_EQ(*NextBand({0, 0}, kBasis, true), (BandDegrees{1, 0}));
  EXPECT_EQ(*NextBand({3, 0}, kBasis, true), (BandDegrees{3, 1}));
  EXPECT_FALSE(NextBand({3, 2}, kBasis, true).has_value());
  EXPECT_FALSE(NextBand({3, 0}, kBasis, false).has_value());
  // Coefficients used minus the DC, times 3 channels.
  EXPECT_EQ(RestColumns({0, 0}, kBasis, 3), 0u);
  EXPECT_EQ(RestColumns({1, 0}, kBasis, 3), 9u);
  EXPECT_EQ(RestColumns({3, 0}, kBasis, 3), 45u);
  EXPECT_EQ(RestColumns({3, 1}, kBasis, 3), 93u);
  EXPECT_EQ(RestColumns({3, 2}, kBasis, 3), 141u);  // the whole row: 47 x 3
}

// Feeds a probe `views` iterations of gradient rows for n Gaussians: the probed band's
// coefficients get bias + noise, the DC term noise alone.
struct Feed {
  std::size_t n = 200;
  int channels = 3;
  std::vector<float> dc, rest;
  std::mt19937 rng{7};
  void Row(const ColorBandGate& gate, double bias) {
    const std::size_t stride = static_cast<std::size_t>(kBasis.coefficients() - 1) * channels;
    dc.assign(n * channels, 0.0f);
    rest.assign(n * stride, 0.0f);
    std::normal_distribution<float> noise(0.0f, 1.0f);
    const std::size_t first = gate.step_columns();
    const std::size_t last = RestColumns(gate.render_degrees(), kBasis, channels);
    for (std::size_t i = 0; i < n; ++i) {
      for (int c = 0; c < channels; ++c) dc[i * channels + c] = noise(rng);
      // Each Gaussian's own sign: agreement is across views, not across Gaussians.
      const float sign = i % 2 ? 1.0f : -1.0f;
      for (std::size_t j = first; j < last; ++j)
        rest[i * stride + j] = static_cast<float>(sign * bias) + noise(rng);
    }
  }
};

std::optional<BandDecision> Probe(ColorBandGate* gate, Feed* feed, int from, double bias) {
  std::optional<BandDecision> d;
  for (int it = from; !d; ++it) {
    gate->Begin(it, feed->n);
    EXPECT_TRUE(gate->probing());
    feed->Row(*gate, bias);
    // Two blocks, as worker threads would hand them.
    const std::size_t stride = static_cast<std::size_t>(kBasis.coefficients() - 1) * 3;
    const auto half = static_cast<std::int64_t>(feed->n / 2);
    gate->Add(0, half, GradientRows{feed->dc.data(), feed->rest.data()});
    gate->Add(half, static_cast<std::int64_t>(feed->n),
              GradientRows{feed->dc.data() + half * 3, feed->rest.data() + half * stride});
    d = gate->End(it, /*rows_move=*/false);
  }
  return d;
}

TEST(ColorBands, NoiseStaysFrozenAgreementSwitchesOn) {
  ColorBandGate gate(kBasis, true, 3, {.interval = 1000, .probe_iterations = 50, .min_signal = 2});
  Feed feed;
  gate.Begin(1000, feed.n);  // the reference adds the band at 1000; the probe starts after it
  EXPECT_FALSE(gate.probing());
  EXPECT_EQ(gate.render_degrees(), (BandDegrees{0, 0}));
  gate.Begin(1001, feed.n);
  ASSERT_TRUE(gate.probing());
  EXPECT_EQ(gate.render_degrees(), (BandDegrees{1, 0}));  // rendered, not stepped
  EXPECT_EQ(gate.step_columns(), 0u);
  const std::optional<BandDecision> noise = Probe(&gate, &feed, 1001, 0.0);
  ASSERT_TRUE(noise.has_value());
  EXPECT_EQ(noise->iteration, 1050);
  EXPECT_NEAR(noise->signal, 1.0, 0.1);    // sum S^2 = sum Q in expectation
  EXPECT_NEAR(noise->dc_signal, 1.0, 0.1);
  EXPECT_FALSE(noise->switched_on);
  EXPECT_EQ(gate.accepted(), (BandDegrees{0, 0}));
  EXPECT_FALSE(gate.probing());
  gate.Begin(1500, feed.n);  // not a point of the schedule
  EXPECT_FALSE(gate.probing());
  // The next point probes the same band again; a bias of half the noise, 50 views: about
  // 1 + 50 x 0.25 / 1.25 = 11.
  const std::optional<BandDecision> agree = Probe(&gate, &feed, 2001, 0.5);
  ASSERT_TRUE(agree.has_value());
  EXPECT_GT(agree->signal, 8.0);
  EXPECT_TRUE(agree->switched_on);
  EXPECT_EQ(gate.accepted(), (BandDegrees{1, 0}));
  EXPECT_EQ(gate.step_columns(), 9u);
  EXPECT_EQ(gate.decisions().size(), 2u);
}

// The DC term's share is taken out first: a residual with a mean (a DC still short of its value)
// makes every band's gradient Y_j r agree in sign even where Y_j is unrelated to the residual;
// that alone must not switch a band on. A residual that follows Y_j does.
TEST(ColorBands, AResidualTheDcTermExplainsIsNoSignal) {
  for (const double follows : {0.0, 1.0}) {
    ColorBandGate gate(kBasis, true, 3, {.interval = 1000, .probe_iterations = 60, .min_signal = 2});
    const std::size_t n = 300, stride = static_cast<std::size_t>(kBasis.coefficients() - 1) * 3;
    std::vector<float> dc(n * 3), rest(n * stride, 0.0f);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> y(0.2f, 0.8f);  // the band's function: mean 0.5
    std::normal_distribution<float> noise(0.0f, 0.3f);
    std::optional<BandDecision> d;
    for (int it = 1001; !d; ++it) {
      gate.Begin(it, n);
      for (std::size_t i = 0; i < n; ++i) {
        const float yi = y(rng);
        for (int c = 0; c < 3; ++c) {
          const float r = 1.0f + static_cast<float>(follows) * (yi - 0.5f) * 4.0f + noise(rng);
          dc[i * 3 + c] = 0.28f * r;
          for (std::size_t j = static_cast<std::size_t>(c); j < 9; j += 3) rest[i * stride + j] = yi * r;
        }
      }
      gate.Add(0, static_cast<std::int64_t>(n), GradientRows{dc.data(), rest.data()});
      d = gate.End(it, false);
    }
    EXPECT_GT(d->dc_signal, 10.0);  // the DC's gradients agree: it is short of its value
    if (follows == 0) {
      EXPECT_NEAR(d->signal, 1.0, 0.15);
      EXPECT_FALSE(d->switched_on);
    } else {
      EXPECT_GT(d->signal, 5.0);
      EXPECT_TRUE(d->switched_on);
    }
  }
}

TEST(ColorBands, ADensificationEndsTheProbe) {
  ColorBandGate gate(kBasis, true, 3, {.interval = 1000, .probe_iterations = 100, .min_signal = 2});
  Feed feed;
  gate.Begin(1001, feed.n);
  feed.Row(gate, 1.0);
  gate.Add(0, static_cast<std::int64_t>(feed.n), GradientRows{feed.dc.data(), feed.rest.data()});
  EXPECT_FALSE(gate.End(1001, false).has_value());
  const std::optional<BandDecision> d = gate.End(1002, /*rows_move=*/true);
  ASSERT_TRUE(d.has_value());
  EXPECT_FALSE(gate.probing());
}

TEST(ColorBands, StaticModelsProbeNoTimeBand) {
  ColorBandGate gate(kBasis, false, 3, {.interval = 10, .probe_iterations = 5, .min_signal = 0});
  Feed feed;
  for (int point = 1; point <= 5; ++point) {
    gate.Begin(point * 10 + 1, feed.n);
    if (!gate.probing()) break;
    Probe(&gate, &feed, point * 10 + 1, 1.0);
  }
  EXPECT_EQ(gate.accepted(), (BandDegrees{3, 0}));  // a threshold of 0 takes every band
  gate.Begin(61, feed.n);
  EXPECT_FALSE(gate.probing());
}

TEST(ColorBands, StateRoundTripsMidProbeAndBadStateIsNamed) {
  const ColorBandGate::Options o{.interval = 1000, .probe_iterations = 10, .min_signal = 2};
  ColorBandGate gate(kBasis, true, 3, o), twin(kBasis, true, 3, o);
  Feed feed, twin_feed;
  gate.Begin(1001, feed.n);
  for (int it = 1001; it < 1005; ++it) {
    feed.Row(gate, 0.3);
    gate.Add(0, static_cast<std::int64_t>(feed.n), GradientRows{feed.dc.data(), feed.rest.data()});
    ASSERT_FALSE(gate.End(it, false).has_value());
  }
  ColorBandGate resumed(kBasis, true, 3, o);
  resumed.FromJson(gate.ToJson(), gate.sums(), feed.n, "run/checkpoint.bin");
  EXPECT_TRUE(resumed.probing());
  EXPECT_EQ(resumed.render_degrees(), gate.render_degrees());
  twin_feed = feed;
  std::optional<BandDecision> a, b;
  for (int it = 1005; !a; ++it) {
    feed.Row(gate, 0.3);
    twin_feed.Row(resumed, 0.3);
    gate.Add(0, static_cast<std::int64_t>(feed.n), GradientRows{feed.dc.data(), feed.rest.data()});
    resumed.Add(0, static_cast<std::int64_t>(feed.n),
                GradientRows{twin_feed.dc.data(), twin_feed.rest.data()});
    a = gate.End(it, false);
    b = resumed.End(it, false);
  }
  ASSERT_TRUE(b.has_value());
  EXPECT_EQ(a->signal, b->signal);  // bit for bit
  EXPECT_EQ(a->switched_on, b->switched_on);

  ColorBandGate bad(kBasis, true, 3, o);
  nlohmann::json j = gate.ToJson();
  j["sh_degree"] = 1;
  j["time_degree"] = 1;  // a time band before the spatial ones are all on
  try {
    bad.FromJson(j, {}, feed.n, "run/checkpoint.bin");
    FAIL() << "accepted a time band before SH degree 3";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("run/checkpoint.bin"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("colour bands out of range"), std::string::npos);
  }
  j = gate.ToJson();
  j["probe_from"] = 1001;
  EXPECT_THROW(bad.FromJson(j, std::vector<float>(3), feed.n, "run/checkpoint.bin"), Error);
  j.erase("decisions");
  EXPECT_THROW(bad.FromJson(j, {}, feed.n, "run/checkpoint.bin"), Error);
}

}  // namespace
}  // namespace hdr4d::method
