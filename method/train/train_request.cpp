#include "method/train/train_request.h"

#include "core/util/error.h"
#include "method/train/resume_check.h"
#include "method/train/train_config.h"

namespace hdr4d::method {
namespace {

// The given options laid over `options` whose target is `target`, in the table's order.
void ApplyGiven(const TrainRequest& request, OptionTarget target, TrainOptions* options) {
  for (const GivenTrainOption& g : request.given) {
    const TrainOption& row = *g.option;
    if (row.target != target) continue;
    // Checked by the command line already; a library caller gets the same words.
    if (std::string problem = row.Check(g.value, /*allow_unset=*/false); !problem.empty())
      Fail("train: {}: {}", row.flag, problem);
    (row.set_given ? row.set_given : row.set)(options, g.value);
  }
}

// The colour model: the resumed run's own unless --method is given, else the method's preset;
// then the tone-mapper and HDR options given.
HdrTrainingOptions ResolveHdr(const TrainRequest& request,
                              const std::optional<TrainOptions>& saved,
                              const MethodPresetFn& preset,
                              TrainOptions options) {
  options.hdr = saved && !request.method ? saved->hdr
                                         : preset(request.method.value_or(request.default_method));
  ApplyGiven(request, OptionTarget::kToneMapper, &options);
  ApplyGiven(request, OptionTarget::kHdr, &options);
  HdrTrainingOptions& hdr = options.hdr;
  // A finished LDR-alone run given --hdr-head becomes the ldr+hdr run with a head whose loop it
  // already trained (AcceptAddedHdrHead).
  if (request.Given("--hdr-head") && saved && !saved->hdr.hdr_head &&
      !request.Given("--supervision") && hdr.supervision == Supervision::kLdr)
    hdr.supervision = Supervision::kLdrHdr;
  if (std::string p = hdr.Validate(); !p.empty()) Fail("train: {}", p);
  return hdr;
}

}  // namespace

bool TrainRequest::Given(const std::string& flag) const {
  for (const GivenTrainOption& g : given) {
    if (g.option->flag == flag) return true;
  }
  return false;
}

TrainOptions ResolveTrainRequest(const TrainRequest& request, const MethodPresetFn& preset) {
  if (request.out.empty()) Fail("train: --out is required");
  // --resume: the run's recorded options, with every option given put over them. What differs
  // from the run's configuration is then refused by the trainer, before the scene is read,
  // except what the table lets a resume change.
  std::optional<TrainOptions> saved;
  if (request.resume) {
    const std::string record = (request.out / "config.json").string();
    saved = TrainOptions::FromJson(ReadSavedRunConfig(request.out), record);
  }
  if (!request.Given("--data") && !saved)
    Fail("train: --data is required (a resumed run takes its own from RUN/config.json)");
  TrainOptions options = saved ? *saved : TrainOptions{};
  bool length_asked = request.Given("--iterations") || request.Given("--stop-window") ||
                      request.Given("--stop-on-val");
  if (!request.config.empty()) {
    const nlohmann::json config = ReadTrainConfig(request.config);
    length_asked |= config.contains("iterations");
    ApplyTrainConfig(config, "--config " + request.config,
                     [&request](const std::string& flag) { return request.Given(flag); },
                     &options);
  }
  ApplyGiven(request, OptionTarget::kRun, &options);
  // No run length asked for: a scene with a val split stops on it (TrainingRun::PickStopForScene).
  options.stop_on_val_where_split = !saved && !options.reference && !length_asked;
  options.out = request.out;
  options.resume = request.resume;
  options.overwrite = request.overwrite;
  options.hdr = ResolveHdr(request, saved, preset, options);
  // --reference reads the radiance bank's unwritten rows as zeros, as before (radiance_bank.h).
  if (options.reference && !saved && options.hdr.tone_mapper &&
      !request.Given("--unseen-bank-rows"))
    options.hdr.tone_mapper->unseen_rows = "zero";
  // Nothing HDR asked for: a scene with one exposure and no HDR truth trains plain 4DGS (a
  // resumed run trains what it started with).
  bool asked_for_hdr = request.method.has_value();
  for (const GivenTrainOption& g : request.given) asked_for_hdr |= g.option->asks_for_hdr;
  if (!asked_for_hdr && !saved) options.when_nothing_hdr = preset(request.ldr_method);
  return options;
}

}  // namespace hdr4d::method
