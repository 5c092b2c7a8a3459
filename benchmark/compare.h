// `hdr4d bench compare`: two sets of runs side by side, so a change to the code can be judged
// against the last release as a table. Side A and side B are two results stores, or two code
// versions in one store (a run's stored code version, or its git hash).
//
// Per configuration (suite x method x scene x supervision x budget x variant) and metric: the
// means of A and B over the seeds both have, B - A, and the paired verdict: the seeds are the
// pairs, tested with PairedSeedTest (benchmark/stats.h); "B better" / "A better" in the
// metric's direction where it exceeds the seed noise, "undecided" where it does not or cannot
// be tested (one seed). Per method over all scenes the pairs are (scene, seed), blocked by
// scene; with one seed per scene the test is over scenes.
#pragma once

#include <string>
#include <vector>

#include "benchmark/results_store.h"
#include "benchmark/stats.h"

namespace hdr4d::bench {

struct CompareSide {
  std::string name;  // how the tables call it: the store's file, or "code version V"
  std::vector<RunSummary> runs;
};

// The runs of one code version in a store: the labelled ones, and the ones a later version's
// run replaced under their labels, matched back to those labels through their run identity
// (the same train / render arguments, data and region, another code version). `version` is a
// prefix of the stored code version or a part of the git description; throws hdr4d::Error
// listing the store's versions when no run matches, or when it matches more than one version.
CompareSide VersionSide(const ResultsStore& store, const std::string& version);
// Every labelled run of a store.
CompareSide StoreSide(const ResultsStore& store);

struct CompareOptions {
  std::string suite;                 // "": every suite
  std::vector<std::string> metrics;  // empty: the paper's columns; {"all"}: every shared key
  double alpha = 0.05;
};

struct CompareLine {
  std::string suite, method, scene, supervision, budget, variant;  // scene "" = over scenes
  std::string metric;
  int direction = 0;  // +1 higher is better, -1 lower, 0 unknown
  double a = 0, b = 0;
  PairedTest test;
  std::string Verdict() const;  // "B better", "A better", "undecided", "same", "differs"
};

struct Comparison {
  std::string a_name, b_name;
  std::vector<CompareLine> per_configuration, per_method;
  std::vector<std::string> notes;  // configurations only one side has, ...
};

Comparison Compare(const CompareSide& a, const CompareSide& b, const CompareOptions& options);

std::string CompareMarkdown(const Comparison& comparison);
std::string CompareCsv(const Comparison& comparison);

}  // namespace hdr4d::bench
