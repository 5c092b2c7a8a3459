// The table formats: Markdown (with the paired tests), LaTeX (booktabs) and tidy CSV.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <string>
#include <vector>

#include "benchmark/csv_field.h"
#include "benchmark/tables.h"

namespace hdr4d::bench {
namespace {

std::string CellText(const Cell& c, const Column& col, bool markdown) {
  if (!col.computable) return "n/a";
  if (!c.has_value) return "-";
  std::string v = FormatValue(c.mean, col.digits);
  if (c.best) v = markdown ? "**" + v + "**" : "\\textbf{" + v + "}";
  if (c.has_spread) v += (markdown ? " ± " : " $\\pm$ ") + FormatValue(c.spread, col.digits);
  if (!c.complete()) v += fmt::format(" [{}/{}]", c.runs, c.expected);
  return v;
}

std::string HeaderOf(const Column& c) {
  return (c.group.empty() ? "" : c.group + " ") + c.label + ArrowOf(c);
}

std::string Join(const std::vector<std::string>& v, const std::string& sep) {
  std::string s;
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? sep : "") + v[i];
  return s;
}

std::string Intro(const Table& t) {
  std::vector<std::string> seeds;
  for (auto s : t.seeds) seeds.push_back(std::to_string(s));
  return fmt::format(
      "Scenes ({}): {}; seeds {}; budget {}{}. HDR columns: {}. Each cell: mean over scenes "
      "(averaged over seeds) ± sample standard deviation over seeds of the mean over scenes; best "
      "per column in bold.",
      t.scenes.size(), t.scenes.empty() ? "none" : Join(t.scenes, ", "), Join(seeds, ", "),
      t.budget, t.variant.empty() ? "" : ", variant " + t.variant, t.protocol);
}

std::string LatexEscape(const std::string& s) {
  std::string out;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const char c = s[i];
    if (s.compare(i, 3, "†") == 0) {
      out += "$^\\dagger$";
      i += 2;
    } else if (s.compare(i, 2, "±") == 0) {
      out += "$\\pm$";
      i += 1;
    } else if (s.compare(i, 3, "↑") == 0) {
      out += "$\\uparrow$";
      i += 2;
    } else if (s.compare(i, 3, "↓") == 0) {
      out += "$\\downarrow$";
      i += 2;
    } else if (std::string("&%$#_{}").find(c) != std::string::npos) {
      out.push_back('\\');
      out.push_back(c);
    } else if (c == '~') {
      out += "\\textasciitilde{}";
    } else if (c == '^') {
      out += "\\textasciicircum{}";
    } else if (c == '\\') {
      out += "\\textbackslash{}";
    } else {
      out += c;
    }
  }
  return out;
}

}  // namespace

std::string ToMarkdown(const Table& t) {
  std::string md = fmt::format("### {}: {}\n\n{}\n\n", t.id, t.title, Intro(t));
  if (!t.note.empty()) md += t.note + "\n\n";
  md += "| Row | Method | Supervision |";
  for (const Column& c : t.columns) md += fmt::format(" {} |", HeaderOf(c));
  md += "\n|---|---|---|";
  for (std::size_t i = 0; i < t.columns.size(); ++i) md += "---|";
  md += "\n";
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const RowResult& r = t.rows[i];
    md += fmt::format("| {} | {} | {} |", i + 1, RowName(r, t.scenes.size()),
                      SupervisionLabel(r.supervision));
    for (std::size_t c = 0; c < t.columns.size(); ++c)
      md += fmt::format(" {} |", CellText(r.cells[c], t.columns[c], true));
    md += "\n";
  }
  if (!t.footnotes.empty()) {
    md += "\n";
    for (const std::string& f : t.footnotes) md += fmt::format("- {}\n", f);
  }
  return md;
}

std::string PairedTestsMarkdown(const Table& t) {
  std::vector<std::size_t> cols;
  for (std::size_t c = 0; c < t.columns.size(); ++c)
    if (t.columns[c].quality && t.columns[c].computable) cols.push_back(c);
  std::string md = fmt::format(
      "Paired tests of {} against '{}': mean difference (row - reference) over the (scene, "
      "seed) pairs both have, two-sided t-test against the seed-to-seed variance of the "
      "differences pooled within scenes (n - scenes degrees of freedom), alpha 0.05.\n\n",
      t.id, t.reference);
  md += "| Row |";
  for (std::size_t c : cols) md += fmt::format(" {} |", HeaderOf(t.columns[c]));
  md += "\n|---|";
  for (std::size_t i = 0; i < cols.size(); ++i) md += "---|";
  md += "\n";
  for (const RowResult& r : t.rows) {
    if (r.is_reference) continue;
    md += fmt::format("| {} |", r.label);
    for (std::size_t c : cols) {
      const PairedTest& p = r.tests[c];
      const char* noise = p.over_scenes ? "scene-to-scene noise" : "seed noise";
      if (p.pairs == 0) {
        md += " - |";
      } else if (!p.testable) {
        md += fmt::format(" {:+.{}f}, n/a (1 seed) |", p.mean_difference, t.columns[c].digits);
      } else {
        md += fmt::format(" {:+.{}f}, p = {:.2g}: {}{} |", p.mean_difference, t.columns[c].digits,
                          p.p, p.significant ? fmt::format("**exceeds {}**", noise)
                                             : fmt::format("within {}", noise),
                          p.over_scenes ? fmt::format(" (over {} scenes)", p.pairs) : "");
      }
    }
    md += "\n";
  }
  return md;
}

std::string ToLatex(const Table& t) {
  std::string spec = "c|l|l";
  std::string prev = "\x01";
  for (const Column& c : t.columns) {
    spec += (c.group != prev || c.group.empty()) ? "|c" : "c";
    prev = c.group;
  }
  std::string tex = "% " + t.id + ": generated by hdr4d bench table\n";
  tex += "\\begin{table}[t]\n\\centering\n";
  std::string caption = LatexEscape(t.title + ". " + Intro(t));
  for (const std::string& f : t.footnotes) caption += " " + LatexEscape(f);
  tex += "\\caption{" + caption + "}\n\\label{tab:" + t.id + "}\n";
  tex += "\\begin{tabular}{" + spec + "}\n\\toprule\n";
  // Group header (HDR / LDR) over the metric columns, then the column names.
  std::string groups = "\\multirow{2}{*}{Row} & \\multirow{2}{*}{Method} & \\multirow{2}{*}{Supervision}";
  std::string names = " & &";
  for (std::size_t c = 0; c < t.columns.size();) {
    std::size_t e = c + 1;
    while (e < t.columns.size() && !t.columns[c].group.empty() && t.columns[e].group == t.columns[c].group) ++e;
    if (t.columns[c].group.empty()) {
      groups += " & " + LatexEscape(t.columns[c].label);
      names += " & " + LatexEscape(ArrowOf(t.columns[c]));
    } else {
      groups += fmt::format(" & \\multicolumn{{{}}}{{c|}}{{{}}}", e - c, t.columns[c].group);
      for (std::size_t k = c; k < e; ++k)
        names += " & " + LatexEscape(t.columns[k].label + ArrowOf(t.columns[k]));
    }
    c = e;
  }
  tex += groups + " \\\\\n" + names + " \\\\\n\\midrule\n";
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const RowResult& r = t.rows[i];
    tex += fmt::format("{} & {} & {}", i + 1, LatexEscape(RowName(r, t.scenes.size())),
                       LatexEscape(SupervisionLabel(r.supervision)));
    for (std::size_t c = 0; c < t.columns.size(); ++c) {
      std::string cell = CellText(r.cells[c], t.columns[c], false);
      if (cell.find('[') != std::string::npos) cell = cell.substr(0, cell.find(" [")) + "$^\\ast$";
      tex += " & " + cell;
    }
    tex += " \\\\\n";
  }
  tex += "\\bottomrule\n\\end{tabular}\n\\end{table}\n";
  return tex;
}

std::string ToCsv(const Table& t) {
  std::string csv =
      "table,row,label,method,supervision,column,key,mean,sd_over_seeds,runs,expected_runs,best,"
      "diff_vs_reference,p_vs_reference,exceeds_seed_noise,protocol,budget,external,"
      "added_row,coverage,test_over\n";
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const RowResult& r = t.rows[i];
    for (std::size_t c = 0; c < t.columns.size(); ++c) {
      const Cell& cell = r.cells[c];
      const PairedTest& p = r.tests[c];
      const Column& col = t.columns[c];
      csv += fmt::format(
          "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", t.id, i + 1,
          CsvField(r.label),
          CsvField(r.method), r.supervision, CsvField(HeaderOf(col)), col.key,
          !col.computable ? "not computable" : cell.has_value ? FormatValue(cell.mean, 6) : "",
          cell.has_spread ? FormatValue(cell.spread, 6) : "", cell.runs, cell.expected,
          cell.best ? 1 : 0, p.pairs ? FormatValue(p.mean_difference, 6) : "",
          p.testable ? fmt::format("{:.6g}", p.p) : "",
          p.testable ? (p.significant ? "yes" : "no") : "", CsvField(t.protocol), t.budget,
          r.external ? 1 : 0, r.added ? 1 : 0, CsvField(CoverageText(r, t.scenes.size())),
          p.testable ? (p.over_scenes ? "scenes" : "seeds") : "");
    }
  }
  return csv;
}

}  // namespace hdr4d::bench
