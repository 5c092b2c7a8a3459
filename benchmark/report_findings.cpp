#include "benchmark/report_findings.h"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "benchmark/findings.h"
#include "benchmark/report_images.h"
#include "benchmark/report_scene.h"

namespace hdr4d::bench {
namespace {

std::string FindingRowHtml(const Finding& f) {
  std::string against;
  for (const FindingComparison& c : f.against) {
    if (!c.has_value) {
      against += HtmlEscape(c.label) + ": no runs<br>";
      continue;
    }
    against += fmt::format("{} {:.3f}", HtmlEscape(c.label), c.mean);
    if (c.test.testable)
      against += fmt::format(" ({:+.3f}, p = {:.2g})", c.test.mean_difference, c.test.p);
    else
      against += " (not testable)";
    against += "<br>";
  }
  const std::string ref = HtmlEscape(ReferenceText(f));
  return fmt::format(
      "<tr><td>{}</td><td>{}</td><td>{}</td><td><b>{}</b></td><td>{}</td><td>{}</td><td>{}</td>"
      "<td>{}/{} scenes ({}), seeds {}</td></tr>\n",
      HtmlEscape(f.claim), HtmlEscape(f.pipeline), HtmlEscape(f.metric), HtmlEscape(f.verdict), ref,
      against, HtmlEscape(f.why), f.scenes_covered.size(), f.table_scenes,
      HtmlEscape(fmt::format("{}", fmt::join(f.scenes_covered, ", "))), fmt::join(f.seeds, ","));
}

}  // namespace

std::string FindingsHtml(const Suite& suite, const std::vector<RunSummary>& runs,
                         const TableOptions& options, int* images, int* tables) {
  FindingsOptions o;
  o.budget = options.budget;
  o.variant = options.variant;
  o.alpha = options.alpha;
  const std::vector<Finding> findings = BuildFindings(suite, runs, o);
  if (findings.empty()) return "";
  std::string h =
      "<p>Per ablation table (one per camera pipeline), and per main table that words a finding, whether "
      "its reference row beats each other row beyond the seed noise (paired test, pairs by scene and seed): <b>holds</b>, "
      "<b>does not hold</b> (some row is better) or <b>undecided</b>; <code>hdr4d bench "
      "findings</code> prints the same lines.</p>\n<table><tr><th>finding</th><th>pipeline</th>"
      "<th>metric</th><th>verdict</th><th>reference</th><th>each other row (row - reference)</th>"
      "<th>why</th><th>covers</th></tr>\n";
  for (const Finding& f : findings) h += FindingRowHtml(f);
  h += "</table>\n";
  ++*tables;
  for (const Finding& f : findings) {
    if (f.metric != "psnr") continue;  // one chart per table: held-out LDR
    const PlotPanel chart = FindingChart(suite, runs, f, o);
    if (chart.first.empty()) continue;
    h += "<div class=\"chart\">" + HtmlImg(PlotDataUri(chart.first, chart.second), chart.second.title) + "</div>\n";
    ++*images;
  }
  return h;
}

}  // namespace hdr4d::bench
