// A pointwise tone mapper baked into tables for a viewer (`hdr4d view`): per channel, its output
// at `nodes` log-HDR values evenly spaced over [x0, x1], for each of a set of radiance-bank rows
// (times) and log exposures. Between nodes and exposures a reader interpolates linearly; beyond
// [x0, x1] and the exposure grid it holds the end values.
#pragma once

#include <vector>

#include "method/tonemap/tone_mapper.h"

namespace hdr4d::method {

struct ToneTables {
  float x0 = 0, x1 = 0;
  int nodes = 0;
  std::vector<int> time_indices;     // the radiance-bank row of each table row, increasing
  std::vector<float> log_exposures;  // natural log, increasing
  // [time row][exposure][node][channel 0..2], channel fastest.
  std::vector<float> values;
  float At(int row, int exposure, int node, int c) const {
    return values[((static_cast<std::size_t>(row) * log_exposures.size() + exposure) * nodes + node) * 3 + c];
  }
};

// Bakes `mapper` (pointwise, checked) over [x0, x1] with `nodes` (>= 2) nodes, at every bank row
// of `num_times` when there are at most `max_rows`, else at `max_rows` rows spread evenly, and
// at `log_exposures`. ToneFrame::image_index is -1 (a view that is no training image).
ToneTables BakeToneTables(ToneMapper* mapper,
                          float x0,
                          float x1,
                          int nodes,
                          int num_times,
                          int max_rows,
                          const std::vector<float>& log_exposures);

// The table's value at log-HDR x, table row `row` and log exposure `log_e` (linear in x and in
// log exposure, held at the ends), channel c: the viewer's lookup, for tests.
float LookUpToneTables(const ToneTables& t, int row, float log_e, float x, int c);

}  // namespace hdr4d::method
