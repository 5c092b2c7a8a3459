// The findings section of the HTML report: `bench findings`' verdict lines (benchmark/
// findings.h) as a table, and per ablation table the chart of held-out LDR PSNR per row with
// its seed spread.
#pragma once

#include <string>
#include <vector>

#include "benchmark/results_store.h"
#include "benchmark/suite.h"
#include "benchmark/tables.h"

namespace hdr4d::bench {

// "" when the suite has no ablation table. Adds the charts it embeds to *images and its tables
// to *tables.
std::string FindingsHtml(const Suite& suite, const std::vector<RunSummary>& runs,
                         const TableOptions& options, int* images, int* tables);

}  // namespace hdr4d::bench
