// Colour bands by need (issue 55): the reference switches on one more colour band every
// sh_increase_interval iterations (spatial SH degrees 1..3, then the time degrees 1..2), whether
// the scene is view- or time-dependent or not; after it 5000 a Gaussian's colour is 144 of the
// 161 floats Adam steps. Here each band starts frozen and is switched on for the whole model
// only when the gradient says the scene needs it.
//
// The test ("probe"): at each point where the reference would switch the next band on, the
// next iterations render with that band added at its value, zero, so the images and the training
// are unchanged; the backward gives the band's gradient, which Adam does not take. A band's
// gradient is g_j = Y_j r and the DC term's g_dc = C0 r, with r the colour's residual. Per
// Gaussian and band coefficient the probe's views give a series g_j, first fitted by the DC's
// series (g_j ~ beta g_dc, least squares: what a DC still short of its value puts into every
// band), leaving e = (Y_j - a weighted mean of Y_j) r. A band the scene does not need leaves e
// whose sign does not persist from view to view (E[(sum e)^2] = E[sum e^2]); a needed one, e that
// agree. The statistic over all Gaussians and coefficients is
//     signal = sum (sum_t e)^2 / sum E_noise[(sum_t e)^2]
// (color_bands.cpp, Decide, for the expectation under noise),
// is about 1 for noise and grows with the views where the colour follows the band; the band is
// switched on when it reaches min_signal, else probed again at the next point. The DC term's own
// ratio (sum g_dc)^2 / sum g_dc^2 is logged beside it. Bands are taken in the reference's order,
// so a frozen band's floats are always the tail of colour_rest that Adam's column limit leaves
// out (RestColumns).
//
// What this is not: a per-Gaussian switch (the other option), nor a freed memory layout
// (frozen floats stay in colour_rest as zeros, so a saved model renders the same at any degree).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "method/gaussian/gaussian_model.h"
#include "method/gaussian/gradient_rows.h"

namespace hdr4d::method {

struct BandDegrees {
  int sh = 0;
  int time = 0;
  bool operator==(const BandDegrees&) const = default;
};

// The reference's schedule: one more spatial degree every `interval` iterations up to the
// maximum, then one more time degree (a static model has none).
BandDegrees ScheduledDegrees(int iteration, const ColorBasis& basis, bool temporal, int interval);

// The band after `d` in that order, or none when every band is on.
std::optional<BandDegrees> NextBand(BandDegrees d, const ColorBasis& basis, bool temporal);

// The leading floats of a colour_rest row the degrees use: coefficients k = n F + lm with
// n <= time and lm < (sh + 1)^2, row index (k - 1) x channels.
std::size_t RestColumns(BandDegrees d, const ColorBasis& basis, int channels);

// One probe's outcome, kept in results.json.
struct BandDecision {
  int iteration = 0;   // the probe's last iteration
  BandDegrees band;    // the degrees with the probed band
  double signal = 0;     // the band's, the DC term's share taken out
  double dc_signal = 0;  // the DC term's own
  bool switched_on = false;
  nlohmann::json ToJson() const;
  static BandDecision FromJson(const nlohmann::json& j);
};

class ColorBandGate {
 public:
  struct Options {
    int interval = 1000;         // sh_increase_interval: where the reference adds a band
    int probe_iterations = 100;  // at most; a densification ends a probe early
    double min_signal = 2.0;
  };
  ColorBandGate(const ColorBasis& basis, bool temporal, int channels, Options options);

  BandDegrees accepted() const { return accepted_; }
  // The degrees to render with: the accepted ones, plus the probed band during a probe.
  BandDegrees render_degrees() const { return probing() ? *candidate_ : accepted_; }
  bool probing() const { return probe_from_ > 0; }
  // Colour_rest floats Adam steps: those of the accepted degrees.
  std::size_t step_columns() const { return RestColumns(accepted_, basis_, channels_); }
  const std::vector<BandDecision>& decisions() const { return decisions_; }

  // Before iteration `it`'s forward: starts a probe of the next band where the reference would
  // add one (it - 1 a positive multiple of the interval) and no probe runs.
  void Begin(int it, std::size_t num_gaussians);
  // Colour gradient rows [b, e) of this iteration's backward (worker threads, disjoint rows).
  void Add(std::int64_t b, std::int64_t e, const GradientRows& rows);
  // After iteration `it`'s backward. The probe ends after probe_iterations, or now when
  // `rows_move` (a densification reorders the Gaussians next); returns its decision.
  std::optional<BandDecision> End(int it, bool rows_move);

  // The state in a checkpoint: the degrees, the probe's start and decisions as JSON, the probe's
  // sums as one float buffer (empty when no probe runs).
  nlohmann::json ToJson() const;
  void FromJson(const nlohmann::json& j, std::vector<float> sums, std::size_t num_gaussians,
                const std::string& source);
  const std::vector<float>& sums() const { return sums_; }

 private:
  // Floats of sums_ per Gaussian: S, P and Q of each band column, S and Q of the DC term's
  // channels, and the views that saw it (Add).
  std::size_t band_columns() const;
  std::size_t row_floats() const { return 3 * band_columns() + 2 * channels_ + 1; }
  BandDecision Decide(int it) const;

  ColorBasis basis_;
  bool temporal_ = false;
  int channels_ = 3;
  Options options_;
  BandDegrees accepted_;
  std::optional<BandDegrees> candidate_;
  int probe_from_ = 0;  // the probe's first iteration; 0: none
  std::vector<float> sums_;
  std::vector<BandDecision> decisions_;
};

}  // namespace hdr4d::method
