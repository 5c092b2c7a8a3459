// Finding and running Blender: the executable (an explicit path, $HDR4D_BLENDER, or `blender` on
// PATH), the bpy scripts (an explicit folder, $HDR4D_DATAGEN_DIR, or this source tree's
// datagen/blender), and a child process whose merged stdout/stderr is streamed line by line.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace hdr4d::datagen {

// `explicit_path` (from --blender) wins, then $HDR4D_BLENDER, then `blender` on PATH. Throws
// hdr4d::Error naming where it looked and how to install Blender when none is found, or naming
// the path when it is not an executable file.
std::filesystem::path FindBlender(const std::string& explicit_path = "");

// The folder holding render_scene.py: `explicit_dir` (from --scripts-dir), then
// $HDR4D_DATAGEN_DIR, then the source tree's datagen/blender. Throws hdr4d::Error when the
// chosen folder lacks render_scene.py.
std::filesystem::path FindScriptsDir(const std::string& explicit_dir = "");

// The name of the entry script inside the scripts folder.
inline constexpr const char* kRenderScript = "render_scene.py";

struct ProcessResult {
  int exit_code = -1;  // when it exited normally
  int signal = 0;      // > 0 when a signal ended it
  bool ok() const { return signal == 0 && exit_code == 0; }
  std::string Describe() const;  // "exit code 3" or "signal 9"
};

// Runs argv (argv[0] is a path, not searched on PATH) with stdin from /dev/null and stdout and
// stderr merged into one pipe; calls on_line for every line (without its newline, also for a
// last unterminated one) as it arrives. Throws hdr4d::Error when the program cannot be started.
// The child dies with hdr4d (PR_SET_PDEATHSIG); SIGINT, SIGTERM or SIGHUP to hdr4d while it runs
// stop it (SIGTERM, SIGKILL after 3 s) and throw hdr4d::Error naming the signal.
ProcessResult RunProcess(const std::vector<std::string>& argv,
                         const std::function<void(const std::string&)>& on_line);

}  // namespace hdr4d::datagen
