// `hdr4d bench compare`'s Markdown and CSV (benchmark/compare.h).
#include <fmt/format.h>

#include <cmath>
#include <string>

#include "benchmark/csv_field.h"
#include "benchmark/compare.h"

namespace hdr4d::bench {
namespace {

std::string Number(double v, const std::string& metric) {
  if (std::isnan(v)) return "";
  if (std::isinf(v)) return "n/a";  // the means are over finite values: no inf reaches here
  const bool fine = metric.find("ssim") != std::string::npos || metric.find("flip") != std::string::npos;
  return fmt::format("{:.{}f}", v, fine ? 4 : 3);
}

std::string CsvNumber(double v) {
  if (std::isnan(v)) return "";
  if (std::isinf(v)) return "n/a";  // the means are over finite values: no inf reaches here
  return fmt::format("{:.6f}", v);
}

std::string PText(const PairedTest& t) {
  if (!t.testable) return t.pairs == 1 ? "n/a (1 pair)" : "n/a (1 seed per scene)";
  return fmt::format("{:.2g}", t.p);
}

std::string TestOver(const PairedTest& t) {
  if (!t.testable) return "";
  return t.over_scenes ? "scenes" : "seeds";
}

std::string MarkdownLines(const std::vector<CompareLine>& lines, bool with_scene) {
  std::string md = with_scene ? "| Suite | Method | Scene | Supervision | Budget | Metric | A | B "
                                "| B - A | Pairs | p | Verdict |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n"
                              : "| Suite | Method | Supervision | Budget | Metric | A | B | B - A "
                                "| Pairs | Test over | p | Verdict |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const CompareLine& l : lines) {
    const std::string verdict = l.Verdict();
    const std::string shown = verdict == "B better" || verdict == "A better" ? "**" + verdict + "**" : verdict;
    const std::string budget = l.budget + (l.variant.empty() ? "" : ", " + l.variant);
    const std::string diff = (l.test.mean_difference > 0 ? "+" : "") + Number(l.test.mean_difference, l.metric);
    if (with_scene) {
      md += fmt::format("| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n", l.suite,
                        l.method, l.scene, l.supervision, budget, l.metric, Number(l.a, l.metric),
                        Number(l.b, l.metric), diff, l.test.pairs, PText(l.test), shown);
    } else {
      md += fmt::format("| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n", l.suite,
                        l.method, l.supervision, budget, l.metric, Number(l.a, l.metric),
                        Number(l.b, l.metric), diff, l.test.pairs, TestOver(l.test), PText(l.test),
                        shown);
    }
  }
  return md;
}

}  // namespace

std::string CompareMarkdown(const Comparison& c) {
  std::string md = fmt::format(
      "### Compare: A = {}, B = {}\n\nPer configuration and metric: the means over the seeds "
      "both have, B - A, and the paired verdict: a two-sided t-test of the differences against "
      "their seed-to-seed spread (alpha 0.05); \"B better\" / \"A better\" in the metric's "
      "direction where the difference exceeds the seed noise, \"undecided\" where it does not "
      "or one seed cannot tell.\n\n",
      c.a_name, c.b_name);
  md += MarkdownLines(c.per_configuration, true);
  md += "\nPer method over every scene both have: pairs by scene and seed, blocked by scene "
        "(over scenes, each a mean over its seeds, where one seed per scene leaves no seed "
        "noise).\n\n";
  md += MarkdownLines(c.per_method, false);
  if (!c.notes.empty()) {
    md += "\n";
    for (const std::string& n : c.notes) md += "- " + n + "\n";
  }
  return md;
}

std::string CompareCsv(const Comparison& c) {
  std::string csv =
      "level,a,b,suite,method,scene,supervision,budget,variant,metric,a_mean,b_mean,b_minus_a,"
      "pairs,test_over,p,verdict\n";
  for (const auto* lines : {&c.per_configuration, &c.per_method}) {
    for (const CompareLine& l : *lines) {
      csv += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
                         lines == &c.per_method ? "method" : "configuration", CsvField(c.a_name),
                         CsvField(c.b_name), CsvField(l.suite), CsvField(l.method),
                         CsvField(l.scene), l.supervision, CsvField(l.budget), CsvField(l.variant),
                         l.metric, CsvNumber(l.a), CsvNumber(l.b),
                         CsvNumber(l.test.mean_difference), l.test.pairs, TestOver(l.test),
                         l.test.testable ? fmt::format("{:.6g}", l.test.p) : "", l.Verdict());
    }
  }
  return csv;
}

}  // namespace hdr4d::bench
