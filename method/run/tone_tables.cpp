#include "method/run/tone_tables.h"

#include <algorithm>
#include <cmath>

#include "core/util/error.h"

namespace hdr4d::method {

ToneTables BakeToneTables(ToneMapper* mapper,
                          float x0,
                          float x1,
                          int nodes,
                          int num_times,
                          int max_rows,
                          const std::vector<float>& log_exposures) {
  HDR4D_CHECK(mapper && mapper->pointwise() && nodes >= 2 && num_times >= 1 && max_rows >= 1);
  HDR4D_CHECK(x1 > x0 && !log_exposures.empty());
  ToneTables t;
  t.x0 = x0;
  t.x1 = x1;
  t.nodes = nodes;
  t.log_exposures = log_exposures;
  const int rows = std::min(num_times, max_rows);
  for (int r = 0; r < rows; ++r) {
    t.time_indices.push_back(rows == 1 ? 0 : static_cast<int>(std::lround(
                                                 double(r) * (num_times - 1) / (rows - 1))));
  }
  // Every channel sees the same x at a node: the input is [x, x, x] per node.
  std::vector<float> x(static_cast<std::size_t>(nodes) * 3), y(x.size());
  for (int k = 0; k < nodes; ++k)
    for (int c = 0; c < 3; ++c) x[k * 3 + c] = x0 + (x1 - x0) * k / (nodes - 1);
  for (int r = 0; r < rows; ++r) {
    for (float log_e : log_exposures) {
      mapper->BeginFrame({t.time_indices[r], -1, log_e});
      mapper->Map(x.data(), nodes, y.data());
      t.values.insert(t.values.end(), y.begin(), y.end());
    }
  }
  return t;
}

float LookUpToneTables(const ToneTables& t, int row, float log_e, float x, int c) {
  const auto& le = t.log_exposures;
  int e0 = 0;
  float we = 0;
  if (le.size() > 1 && log_e > le.front()) {
    if (log_e >= le.back()) {
      e0 = static_cast<int>(le.size()) - 1;
    } else {
      e0 = static_cast<int>(std::upper_bound(le.begin(), le.end(), log_e) - le.begin()) - 1;
      we = (log_e - le[e0]) / (le[e0 + 1] - le[e0]);
    }
  }
  const float u = std::clamp((x - t.x0) / (t.x1 - t.x0), 0.0f, 1.0f) * (t.nodes - 1);
  const int k0 = std::min(static_cast<int>(u), t.nodes - 2);
  const float wk = u - k0;
  auto at_e = [&](int e) { return (1 - wk) * t.At(row, e, k0, c) + wk * t.At(row, e, k0 + 1, c); };
  const float v0 = at_e(e0);
  return we > 0 ? (1 - we) * v0 + we * at_e(e0 + 1) : v0;
}

}  // namespace hdr4d::method
