#include "method/train/initialise.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>

#include "core/util/error.h"
#include "core/util/parallel.h"
#include "method/gaussian/constants.h"
#include "method/optim/lr_schedule.h"

namespace hdr4d::method {

void InitOptions::Validate() const {
  if (num_random_points < kMinInitialPoints)
    Fail("initialisation: need at least {} random points, got {}", kMinInitialPoints,
         num_random_points);
  if (!(random_half_extent > 0))
    Fail("initialisation: random extent must be positive, got {}", random_half_extent);
  if (!(time_max >= time_min))
    Fail("initialisation: time range [{}, {}] is empty", time_min, time_max);
  if (!(time_duration > 0))
    Fail("initialisation: time duration must be positive, got {}", time_duration);
  if (!(initial_opacity > 0 && initial_opacity < 1))
    Fail("initialisation: opacity {} must be in (0, 1)", initial_opacity);
  if (channels < 1) Fail("initialisation: need at least one colour channel");
}

namespace {

// A k-d tree over point indices (median splits on the widest axis), queried for the 3 nearest
// neighbours with branch pruning: exact, and robust for flat or degenerate clouds where a
// uniform grid would need huge numbers of cells.
class KdTree {
 public:
  explicit KdTree(const std::vector<Eigen::Vector3f>& points)
      : points_(points), order_(points.size()) {
    for (std::size_t i = 0; i < order_.size(); ++i) order_[i] = static_cast<std::uint32_t>(i);
    nodes_.reserve(2 * points.size() / kLeafSize + 2);
    Build(0, order_.size());
  }

  // The three smallest squared distances from point `self` to the others (inf when missing).
  std::array<float, 3> ThreeNearest(std::uint32_t self) const {
    std::array<float, 3> best = {kInf, kInf, kInf};
    Search(0, self, best);
    return best;
  }

 private:
  static constexpr std::size_t kLeafSize = 8;
  static constexpr float kInf = std::numeric_limits<float>::infinity();
  struct Node {
    std::uint32_t begin, end;  // range of order_
    int axis = -1;             // -1: leaf
    float split = 0;
    std::uint32_t left = 0, right = 0;
  };

  std::uint32_t Build(std::size_t begin, std::size_t end) {
    const std::uint32_t id = static_cast<std::uint32_t>(nodes_.size());
    nodes_.push_back({static_cast<std::uint32_t>(begin), static_cast<std::uint32_t>(end)});
    if (end - begin <= kLeafSize) return id;
    Eigen::Vector3f lo = points_[order_[begin]], hi = lo;
    for (std::size_t i = begin; i < end; ++i)
      lo = lo.cwiseMin(points_[order_[i]]), hi = hi.cwiseMax(points_[order_[i]]);
    int axis = 0;
    (hi - lo).maxCoeff(&axis);
    const std::size_t mid = (begin + end) / 2;
    std::nth_element(
        order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
        [&](std::uint32_t a, std::uint32_t b) { return points_[a][axis] < points_[b][axis]; });
    const float split = points_[order_[mid]][axis];
    const std::uint32_t left = Build(begin, mid);
    const std::uint32_t right = Build(mid, end);
    Node& node = nodes_[id];
    node.axis = axis;
    node.split = split;
    node.left = left;
    node.right = right;
    return id;
  }

  void Search(std::uint32_t id, std::uint32_t self, std::array<float, 3>& best) const {
    const Node& node = nodes_[id];
    const Eigen::Vector3f& p = points_[self];
    if (node.axis < 0) {
      for (std::uint32_t i = node.begin; i < node.end; ++i) {
        const std::uint32_t j = order_[i];
        if (j == self) continue;
        const float d2 = (points_[j] - p).squaredNorm();
        if (d2 < best[2]) {
          best[2] = d2;
          if (best[2] < best[1]) std::swap(best[1], best[2]);
          if (best[1] < best[0]) std::swap(best[0], best[1]);
        }
      }
      return;
    }
    const float diff = p[node.axis] - node.split;
    const std::uint32_t near = diff < 0 ? node.left : node.right;
    const std::uint32_t far = diff < 0 ? node.right : node.left;
    Search(near, self, best);
    if (diff * diff <= best[2]) Search(far, self, best);
  }

  const std::vector<Eigen::Vector3f>& points_;
  std::vector<std::uint32_t> order_;
  std::vector<Node> nodes_;
};

}  // namespace

std::vector<float> MeanSquaredDistanceToThreeNearest(const std::vector<Eigen::Vector3f>& points) {
  const std::size_t n = points.size();
  std::vector<float> result(n, 1e-7f);
  if (n < 2) return result;
  const KdTree tree(points);
  ParallelFor(static_cast<std::int64_t>(n), 512, [&](std::int64_t i) {
    const std::array<float, 3> best = tree.ThreeNearest(static_cast<std::uint32_t>(i));
    int found = 0;
    float sum = 0;
    for (float d : best) {
      if (std::isfinite(d)) sum += d, ++found;
    }
    result[i] = std::max(found > 0 ? sum / found : 1e-7f, 1e-7f);
  });
  return result;
}

void SubsamplePointCloud(PointCloud* cloud, std::size_t max_points) {
  const std::size_t n = cloud->size();
  if (max_points == 0 || n <= max_points) return;
  PointCloud kept;
  kept.positions.reserve(max_points);
  for (std::size_t k = 0; k < max_points; ++k) {
    const std::size_t i = static_cast<std::size_t>((static_cast<unsigned __int128>(k) * n) / max_points);
    kept.positions.push_back(cloud->positions[i]);
    if (cloud->has_colors()) kept.colors.push_back(cloud->colors[i]);
    if (cloud->has_times()) kept.times.push_back(cloud->times[i]);
  }
  *cloud = std::move(kept);
}

GaussianModel InitialiseGaussians(const std::optional<PointCloud>& cloud,
                                  const InitOptions& options) {
  options.Validate();
  std::mt19937_64 rng(options.seed);
  std::vector<Eigen::Vector3f> positions;
  std::vector<Eigen::Vector3f> colors;
  std::vector<float> times;
  if (cloud && cloud->size() >= static_cast<std::size_t>(kMinInitialPoints)) {
    positions = cloud->positions;
    colors = cloud->colors;
    times = cloud->times;
  } else {
    std::uniform_real_distribution<float> u(-options.random_half_extent,
                                            options.random_half_extent);
    positions.resize(options.num_random_points);
    for (auto& p : positions) p = Eigen::Vector3f(u(rng), u(rng), u(rng));
  }
  const std::size_t n = positions.size();
  if (options.temporal && times.size() != n) {
    std::uniform_real_distribution<float> ut(options.time_min, options.time_max);
    times.resize(n);
    for (float& t : times) t = ut(rng);
  }

  GaussianModel model;
  model.temporal = options.temporal;
  model.color_mode = options.color_mode;
  model.basis = options.basis;
  if (!options.temporal) model.basis.max_time_degree = 0;
  model.channels = options.channels;
  model.Resize(n);
  const std::vector<float> dist2 = MeanSquaredDistanceToThreeNearest(positions);
  // Sigma_tt = T / 5, i.e. a temporal standard deviation of sqrt(T / 5).
  const float log_scale_t = 0.5f * std::log(options.time_duration / 5.0f);
  const float logit = std::log(options.initial_opacity / (1.0f - options.initial_opacity));
  for (std::size_t i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) model.xyz[i * 3 + a] = positions[i][a];
    model.t[i] = options.temporal ? times[i] : 0.0f;
    const float log_scale = 0.5f * std::log(dist2[i]);  // log sqrt(mean squared distance)
    for (int a = 0; a < 3; ++a) model.log_scales[i * 4 + a] = log_scale;
    model.log_scales[i * 4 + 3] = log_scale_t;
    model.opacity_logit[i] = logit;
    // DC coefficient from the point colour: colour = C0 * dc + 0.5 (grey without colours).
    for (int c = 0; c < options.channels; ++c) {
      float rgb = colors.size() == n ? colors[i][std::min(c, 2)] : 0.5f;
      float target =
          options.color_mode == ColorMode::kLogHdr ? std::log(std::max(rgb, 1e-4f)) : rgb;
      model.color_dc[i * options.channels + c] = (target - kColorOffset) / kShC0;
    }
  }
  return model;
}

float ShiftLogColoursToLevel(GaussianModel* model, float log_level) {
  HDR4D_CHECK(model->color_mode == ColorMode::kLogHdr && std::isfinite(log_level));
  const int channels = model->channels;
  const std::size_t n = model->size();
  if (n == 0) return 0.0f;
  std::vector<float> logs(n * channels);
  for (std::size_t i = 0; i < logs.size(); ++i)
    logs[i] = kShC0 * model->color_dc[i] + kColorOffset;
  auto mid = logs.begin() + static_cast<std::ptrdiff_t>(logs.size() / 2);
  std::nth_element(logs.begin(), mid, logs.end());
  const float shift = log_level - *mid;
  for (std::size_t i = 0; i < n * channels; ++i) model->color_dc[i] += shift / kShC0;
  return shift;
}

}  // namespace hdr4d::method
