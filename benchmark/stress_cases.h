// The stress cases by category (benchmark/stress.h lists what they cover). Each group appends
// its cases in the order they run; Cases() (stress_cases.cpp) strings the groups together.
#pragma once

#include <utility>
#include <vector>

#include "benchmark/stress_kit.h"

namespace hdr4d::bench::stress {

inline void AddCase(
    std::vector<Case>& cases, const char* name, const char* category, const char* what, CaseFn fn) {
  cases.push_back({{name, category, what}, std::move(fn)});
}

// stress_cases_extreme.cpp
void AddExtremeExposureCases(std::vector<Case>& cases);
void AddExtremeRadianceCases(std::vector<Case>& cases);
// stress_cases_degenerate.cpp
void AddDegenerateGaussianCases(std::vector<Case>& cases);
void AddDegenerateSceneCases(std::vector<Case>& cases);
// stress_cases_corrupt.cpp
void AddCorruptInputCases(std::vector<Case>& cases);
void AddCorruptSubmissionCase(std::vector<Case>& cases);
// stress_cases_killed.cpp
void AddKilledStateCases(std::vector<Case>& cases);

}  // namespace hdr4d::bench::stress
