// The test metrics of a model during and after training: every view rendered, the LDR metrics
// of its final LDR image and, where it has HDR ground truth, the HDR metrics of its HDR render
// (raw and scale-aligned, core/metrics/hdr_alignment.h), averaged as hdr4d eval does.
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <vector>

#include "method/train/train_views.h"
#include "method/render/view_renderer.h"

namespace hdr4d::method {

// Means over the views of the LDR metrics of the final LDR render and, where a view has HDR
// ground truth, of the HDR metrics of the HDR render (PSNR as the mean of per-view values, 3DGS).
// `with_flip`: also "flip" (LDR-FLIP) and "hdr_flip" (HDR-FLIP, core/metrics/flip.h). At
// 800x800 they cost about 0.2 s of a core per view and per HDR exposure, as much as the rest of
// an evaluation, so the trainer computes them for results.json only, not for the test curve.
// A metric that is not finite for a view (a slope with no measured pixel) is left out of its mean.
nlohmann::json EvaluateViews(ViewRenderer* renderer,
                             const std::vector<TrainView>& views,
                             bool with_flip = true);

// The same for any renderer (the grid family's, baselines/hexplane): `render` draws view `v` at
// its own time and exposure into ldr (H x W x 3 in [0, 1], left empty when the model has no LDR
// output) and, when hdr is not null, the linear HDR render (left empty for an LDR model).
using RenderViewFn =
    std::function<void(const TrainView& v, std::vector<float>* ldr, std::vector<float>* hdr)>;
nlohmann::json EvaluateViews(const RenderViewFn& render,
                             const std::vector<TrainView>& views,
                             bool with_flip = true);

// The mean LDR PSNR over the views, exactly EvaluateViews's "psnr" (the same LDR renders, the
// same per-view values added in the same order, a view with no finite value left out; NaN when
// none has one), without its other metrics or any HDR render: what the val stop reads, without
// what it does not (each HDR truth read from disk again, the HDR metrics and the SSIMs).
double MeanLdrPsnr(ViewRenderer* renderer, const std::vector<TrainView>& views);
double MeanLdrPsnr(const RenderViewFn& render, const std::vector<TrainView>& views);

}  // namespace hdr4d::method
