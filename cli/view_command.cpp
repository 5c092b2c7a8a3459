// hdr4d view: a trained run as one self-contained HTML page with a WebGL viewer.
#include <fmt/format.h>

#include "cli/commands.h"
#include "cli/flags.h"
#include "core/files/atomic_file.h"
#include "core/files/output_guard.h"
#include "method/run/render_split.h"
#include "method/run/viewer_page.h"

namespace hdr4d::cli {

void AddViewCommand(CLI::App& app) {
  auto run = std::make_shared<std::string>();
  auto out = std::make_shared<std::string>();
  auto options = std::make_shared<method::ViewerPageOptions>();
  CLI::App* cmd = app.add_subcommand(
      "view",
      "Write a trained run as one HTML page that renders its Gaussians in the browser (WebGL 2, "
      "no network: script and data inline): the dataset's cameras and mouse orbit, a time slider "
      "and play, an exposure slider, LDR (the run's own pointwise tone mapper, baked into tables "
      "over times and exposures) or HDR (exposure x radiance as sRGB). docs/viewer.md");
  cmd->add_option("run", *run, "Run folder (from hdr4d train)")->required()->check(Text("a run folder"));
  cmd->add_option("--out,-o", *out, "Output .html (default RUN/view.html)")
      ->check(Text("an output .html file"));
  cmd->add_option("--title", options->title, "Page title (default: the run folder's name)")
      ->check(Text("a title"));
  cmd->add_option("--tone-nodes", options->tone_nodes, "Log-HDR nodes of each baked tone curve")
      ->check(Integer(2, 65536))
      ->capture_default_str();
  cmd->add_option("--exposure-steps", options->exposure_steps,
                  "Exposures baked, log-spaced from 1/4 of the shortest to 4x the longest")
      ->check(Integer(2, 1024))
      ->capture_default_str();
  cmd->callback([run, out, options] {
    const std::filesystem::path path =
        out->empty() ? std::filesystem::path(*run) / "view.html" : std::filesystem::path(*out);
    method::ProtectRunInputs(*run);
    method::LoadedRun loaded = method::LoadRun(*run);
    CheckOutputFile(path);
    method::ViewerPageOptions o = *options;
    if (o.title.empty()) o.title = std::filesystem::path(*run).lexically_normal().filename().string();
    if (o.title.empty()) o.title = std::filesystem::absolute(*run).parent_path().filename().string();
    const std::string page = method::ViewerPageHtml(loaded, o);
    WriteFileAtomic(path, [&](std::ostream& s) { s << page; });
    fmt::print("view: {} Gaussians -> {} ({:.1f} MB; {})\n", loaded.model.size(), path.string(),
               page.size() / 1e6, method::ViewerLdrNote(loaded));
  });
}

}  // namespace hdr4d::cli
