#include "baselines/hexplane/ray_batch.h"

#include "baselines/hexplane/ray_batch_lane.h"
#include <algorithm>
#include <cmath>
#include <optional>

#include "baselines/hexplane/background_env.h"
#include "baselines/hexplane/volume_render.h"
#include "baselines/sigmoid_tone_mapper.h"
#include "core/util/error.h"
#include "core/util/parallel.h"

namespace hdr4d::baselines::hexplane {
int RayChannels(const HexPlaneModel& m) { return m.config.color == ColorModel::kLdr ? 3 : 6; }

// Samples of one ray in the box and kept by the occupancy grid, their density features, and
// the compositing weights; stops once the transmittance is below the weight threshold (every
// later sample's weight would be under it, and the reference gives those no colour).
void RayBatch::Lane::March(const HexPlaneModel& m, const Ray& ray, const float* jitter) {
  const HexPlaneConfig& c = m.config;
  const int n = m.NumSamples();
  const float spacing = (c.far - c.near) / float(n - 1), inv_box = 1.0f / c.box;
  const std::size_t start = feature.size();
  float scratch[512];
  std::vector<float> big;
  float* s = scratch;
  if (2 * c.density_comps > 512) {
    big.resize(2 * c.density_comps);
    s = big.data();
  }
  float transmittance_now = 1.0f;
  for (int k = 0; k < n && transmittance_now >= c.weight_threshold; ++k) {
    const float z = c.near + spacing * (k + (jitter ? jitter[k] * (n - 1) / float(n) : 0.0f));
    float p[3];
    bool inside = true;
    for (int a = 0; a < 3; ++a) {
      p[a] = (ray.origin[a] + ray.dir[a] * z - c.center[a]) * inv_box;
      inside = inside && p[a] >= -1.0f && p[a] <= 1.0f;
    }
    if (!inside || !m.occupancy.Keeps(p)) continue;
    const float f = DensityFeature(m.density, m.density_basis, MakePointTaps(m.density, p, ray.time), s);
    // The next sample's z minus this one's (the jitter is per position), 0 for the last.
    const float z_next =
        k + 1 < n ? c.near + spacing * (k + 1 + (jitter ? jitter[k + 1] * (n - 1) / float(n) : 0.0f))
                  : z;
    xyz.insert(xyz.end(), p, p + 3);
    feature.push_back(f);
    delta.push_back((z_next - z) * c.distance_scale);
    const float sigma = Softplus(f + c.density_shift);
    transmittance_now *= std::exp(-sigma * delta.back());
  }
  const int count = int(feature.size() - start);
  alpha.resize(feature.size());
  weight.resize(feature.size());
  transmittance.push_back(CompositeWeights(feature.data() + start, delta.data() + start, count,
                                           c.density_shift, alpha.data() + start,
                                           weight.data() + start));
  first.push_back(int(feature.size()));
}

void RayBatch::Lane::Background(const HexPlaneModel& m, const std::vector<Ray>& rays) {
  const int K = RayChannels(m), num_rays = end - begin;
  background.resize(std::size_t(num_rays) * K);
  if (m.background.empty()) {
    std::fill(background.begin(), background.end(), m.config.background);
    return;
  }
  background_pre.resize(std::size_t(num_rays) * 3);
  const int n = int(m.background.size() / 3);
  for (int i = 0; i < num_rays; ++i) {
    const Ray& ray = RayOf(rays, i);
    BackgroundForward(m.background.data(), n, ray.dir, K, m.OffsetOf(ray.image), ray.log_exposure,
                      kMaxLogRadiance, &background_pre[3 * std::size_t(i)],
                      &background[std::size_t(i) * K]);
  }
}

void RayBatch::Lane::BackgroundBackward(const HexPlaneModel& m, const std::vector<Ray>& rays,
                                        const float* dL_dout) {
  if (m.background.empty()) return;
  const int K = RayChannels(m), n = int(m.background.size() / 3);
  for (int i = 0; i < end - begin; ++i) {
    const Ray& ray = RayOf(rays, i);
    float dbg[6];  // out = ... + T_n background
    const float* dout = dL_dout + std::size_t(begin + i) * K;
    for (int k = 0; k < K; ++k) dbg[k] = transmittance[i] * dout[k];
    float doffset = 0;
    hexplane::BackgroundBackward(n, ray.dir, K, m.OffsetOf(ray.image), ray.log_exposure,
                                 kMaxLogRadiance, &background_pre[3 * std::size_t(i)], dbg,
                                 grads->background.data(), &doffset);
    if (ray.image >= 0 && ray.image < int(grads->exposure_offset.size()))
      grads->exposure_offset[ray.image] += doffset;
  }
}

RayBatch::RayBatch() = default;
RayBatch::~RayBatch() = default;

void RayBatch::Forward(const HexPlaneModel& m, const std::vector<Ray>& rays, const float* jitter,
                       std::vector<float>* out) {
  rays_ = &rays;
  const int n = int(rays.size());
  const int lanes = std::max(1, std::min(MaxThreads(), n / 32 + 1));
  lanes_.resize(lanes);
  const int K = RayChannels(m);
  out->assign(std::size_t(n) * K, 0.0f);
  ParallelFor(lanes, 1, [&](std::int64_t l) {
    if (!lanes_[l]) lanes_[l] = std::make_unique<Lane>();
    Lane& lane = *lanes_[l];
    lane.begin = int(std::int64_t(n) * l / lanes);
    lane.end = int(std::int64_t(n) * (l + 1) / lanes);
    lane.first.assign(1, 0);
    for (auto* v : {&lane.xyz, &lane.feature, &lane.delta, &lane.alpha, &lane.weight,
                    &lane.transmittance})
      v->clear();
    for (int r = lane.begin; r < lane.end; ++r) lane.March(m, rays[r], jitter);
    lane.Appearance(m, rays, jitter ? kExploreSamples : 0, jitter ? jitter[0] : 0.0f);
    lane.Background(m, rays);
    lane.CompositeRays(m, out->data());
  });
}

void RayBatch::Lane::CompositeRays(const HexPlaneModel& m, float* out) const {
  const int K = RayChannels(m);
  for (int r = begin; r < end; ++r) {
    const int i = r - begin, b = first[i];
    Composite(weight.data() + b, colour.data() + std::size_t(b) * K, first[i + 1] - b, K,
              transmittance[i], background.data() + std::size_t(i) * K,
              out + std::size_t(r) * K);
  }
}

void RayBatch::Reexpose(const HexPlaneModel& m, const std::vector<Ray>& rays,
                        std::vector<float>* out) {
  const std::size_t rendered = lanes_.empty() || !lanes_.back() ? 0 : lanes_.back()->end;
  if (rendered == 0 || rays.size() != rendered)
    Fail("hexplane: Reexpose needs the last Forward's rays ({} given, {} rendered)", rays.size(),
         rendered);
  rays_ = &rays;
  out->assign(rays.size() * std::size_t(RayChannels(m)), 0.0f);
  ParallelFor(std::int64_t(lanes_.size()), 1, [&](std::int64_t l) {
    Lane& lane = *lanes_[l];
    lane.ToneMap(m, rays);
    lane.Background(m, rays);
    lane.CompositeRays(m, out->data());
  });
}

std::int64_t RayBatch::density_samples() const {
  std::int64_t n = 0;
  for (const auto& l : lanes_) n += l ? std::int64_t(l->feature.size()) : 0;
  return n;
}

std::int64_t RayBatch::app_samples() const {
  std::int64_t n = 0;
  for (const auto& l : lanes_) n += l ? std::int64_t(l->app_sample.size()) : 0;
  return n;
}

void RayBatch::Backward(const HexPlaneModel& m, const std::vector<float>& dL_dout,
                        HexPlaneGrads* grads) {
  ParallelFor(std::int64_t(lanes_.size()), 1, [&](std::int64_t l) {
    Lane& lane = *lanes_[l];
    if (!lane.grads || lane.grads->mlp.size() != m.mlp.size() ||
        lane.grads->density.space[0].size() != m.density.space[0].size() ||
        lane.grads->density.time[0].size() != m.density.time[0].size()) {
      lane.grads.emplace(m);
    } else {
      lane.grads->SetZero();
    }
    lane.Backward(m, *rays_, dL_dout.data());
  });
  *grads = *lanes_[0]->grads;
  for (std::size_t l = 1; l < lanes_.size(); ++l) grads->Add(*lanes_[l]->grads);
}

}  // namespace hdr4d::baselines::hexplane
