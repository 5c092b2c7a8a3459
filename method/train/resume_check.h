// Resuming a run (hdr4d train --resume): the configuration asked for now against the one the
// run was started with, checked before anything is read from the checkpoint or written.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>

#include "method/optim/lr_schedule.h"

namespace hdr4d::method {

// RUN/config.json as the run wrote it; errors name the file (missing: "nothing to resume").
nlohmann::json ReadSavedRunConfig(const std::filesystem::path& run);

// Schedules left to follow the run length (kFollowRunLength) take the values the run resolved
// when it started, so a resumed run continues the schedule it was on, whatever --iterations
// says now; a schedule given explicitly stays as given (and must then match, below). So do the
// many-view schedule's colour interval and clone correction (optim/lr_schedule.h).
void KeepSavedSchedules(const nlohmann::json& saved, OptimizationOptions* requested);

// A run trained with supervision ldr and resumed with --hdr-head (supervision ldr+hdr): the head's
// training loop is LDR alone's exactly (ResolveHdrTraining), so the run continues as such a run
// and fits the head once its steps are done. Rewrites `saved` (the record, in memory) to what the
// head run records, so that every other option must still match; returns whether it did. Any
// other change of supervision or of the head is left to RequireSame*Config to refuse.
bool AcceptAddedHdrHead(nlohmann::json* saved, const nlohmann::json& requested_hdr);

// Throws hdr4d::Error naming `config_file` and the first key (a dotted path) whose value differs
// between the saved and the requested configuration. Allowed to differ: what decides how long
// and how fast the run goes and how often it reports, not what it learns: the options the
// table marks so (train_options_table.h: threads, test_every, checkpoint_every, max_seconds,
// optimization.iterations). Keys the saved file lacks (runs
// from older versions) are not compared. `data` is compared as a canonical path.
void RequireSameConfig(const nlohmann::json& saved,
                       const nlohmann::json& requested,
                       const std::filesystem::path& config_file);
// The same check over the keys `requested` holds only (the options as given, before the scene is
// read and the schedules resolved): a resume that asks for another configuration is refused
// before the scene's images are loaded.
void RequireSameGivenConfig(const nlohmann::json& saved,
                            const nlohmann::json& requested,
                            const std::filesystem::path& config_file);

// The checkpoint's trainer state holds the record of the run that wrote it (runs since stop 94),
// under this key.
inline constexpr const char* kRunConfigKey = "run_config";

// Throws hdr4d::Error naming both files and the first key whose value in `config` (RUN/config.json
// as read now) differs from the record in `trainer` (the checkpoint's trainer state): an edited
// config.json, or another run's checkpoint.bin, would otherwise resume or render a model under
// settings it was not trained with (a crash, or wrong images). Not compared: what may change on
// resume (as above), and `data` (a scene may move; data_checksums.json tells whether it is the
// same). A checkpoint without the record (runs from before it) is not checked.
void RequireCheckpointOfThisConfig(const nlohmann::json& trainer,
                                   const nlohmann::json& config,
                                   const std::filesystem::path& config_file,
                                   const std::filesystem::path& checkpoint_file);

}  // namespace hdr4d::method
