// The trainer's check for a learned tone curve that has gone flat over the inputs the scene
// gives it (FindFlatToneCurves): every LDR value the same, so no LDR loss can bring it back and
// training would go on to the end with LDR images of one colour. Found with HDR-GS's
// unconstrained static MLP under the joint LDR+HDR term on the `studio` scene (its sigmoid
// saturated at 1 everywhere: 2.25 dB held out; docs/history/accuracy.md); the run is kept as it
// is (that curve is the baseline as published) and the user is told, with the way out.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "method/gaussian/gaussian_model.h"
#include "method/tonemap/tone_curve_samples.h"
#include "method/train/train_views.h"

namespace hdr4d::method {

// Iterations between two checks during training (the run's end is always checked).
inline constexpr int kToneCurveCheckEvery = 500;

// The inputs x = log radiance + log exposure the curves meet in training: the 1st to 99th
// percentile of the Gaussians' constant log colour (their DC term; log-HDR colours) widened by
// the training views' smallest and largest log exposure.
std::pair<double, double> ToneCurveInputRange(const GaussianModel& model,
                                              const std::vector<TrainView>& views);

// The warning shown and recorded in results.json for the flat curves (at least one) found after
// `iteration`.
std::string FlatToneCurveWarning(const std::vector<FlatToneCurve>& flat,
                                 const std::string& tone_mapper_kind,
                                 std::pair<double, double> range,
                                 int iteration);

}  // namespace hdr4d::method
