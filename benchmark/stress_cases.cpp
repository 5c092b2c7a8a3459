// Every stress case, in the order they run; the cases themselves live by category in
// stress_cases_*.cpp (benchmark/stress.h lists what they cover).
#include "benchmark/stress_cases.h"

namespace hdr4d::bench::stress {

std::vector<Case> Cases() {
  std::vector<Case> cases;
  AddExtremeExposureCases(cases);
  AddExtremeRadianceCases(cases);
  AddDegenerateGaussianCases(cases);
  AddDegenerateSceneCases(cases);
  AddCorruptInputCases(cases);
  AddKilledStateCases(cases);
  AddCorruptSubmissionCase(cases);
  return cases;
}

}  // namespace hdr4d::bench::stress
