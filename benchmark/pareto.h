// Run time against error (`hdr4d bench pareto`): every configuration of a suite (method x
// supervision x variant x budget, averaged over seeds) as a point of training time (or render
// time per frame) against a quality metric, per scene and over all scenes, with the Pareto
// front: the configurations no other one beats on both time and quality. Charts are drawn with
// core's plot library as PNG and SVG; the points go to a CSV.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "benchmark/results_store.h"
#include "benchmark/suite.h"
#include "core/viz/plot.h"

namespace hdr4d::bench {

struct ParetoPoint {
  std::string method, supervision, variant, budget;
  std::string scene;  // "" for the overall points (means over scenes)
  double seconds = 0;  // training seconds, or render milliseconds per frame
  double quality = 0;  // the metric (higher is better)
  int seeds = 0;
  bool front = false;
  // The variant trains `hdr4d train --reference` (the paper-faithful configuration): its points
  // have a front of their own beside the default's (issue 55), both drawn.
  bool reference = false;
  bool family_front = false;  // on the front of its family (reference or default) alone
  std::string Config() const;  // "method/supervision[/variant]"
};

enum class ParetoTime { kTraining, kRender };

// Points of one scene (or, with scene "", of the means over the scenes every configuration has
// runs on), front flags set. Runs without the metric or the time are left out.
std::vector<ParetoPoint> ParetoPoints(const std::vector<RunSummary>& runs, const Suite& suite,
                                      const std::string& metric, ParetoTime time,
                                      const std::string& scene);

// Marks the points that no other point dominates (time <= and quality >=, one strictly).
void MarkFront(std::vector<ParetoPoint>* points);
// Sets family_front: the front of the --reference points and that of the others, apart.
void MarkFamilyFronts(std::vector<ParetoPoint>* points);
// Whether the suite's variant of this name trains with --reference.
bool ReferenceVariant(const Suite& suite, const std::string& variant);

// The chart of one scene ("" = overall) and time: one line per configuration through its
// budgets, the front in black; with --reference variants, the default's front in black and the
// reference's in grey. False when there is no point to draw.
bool ParetoChart(const std::vector<RunSummary>& runs, const Suite& suite, const std::string& metric,
                 ParetoTime time, const std::string& scene, std::vector<PlotSeries>* series,
                 PlotOptions* options);

struct ParetoOptions {
  std::string metric = "mu_psnr";
  std::filesystem::path out;
};

// Writes OUT/pareto_<scene>_<train|render>.{png,svg} per scene and for "overall", and
// OUT/pareto.csv; returns the chart paths (PNG).
std::vector<std::filesystem::path> WritePareto(const std::vector<RunSummary>& runs,
                                               const Suite& suite, const ParetoOptions& options);

}  // namespace hdr4d::bench
