// Adam over the HexPlane model's parameter arrays (PyTorch's, eps 1e-8, the reference's betas
// 0.9 / 0.99), one learning rate per array. Its moments are dropped when the planes are
// upsampled: the reference builds a new optimiser then.
#pragma once

#include <cmath>
#include <vector>

#include "baselines/hexplane/binary_io.h"
#include "core/util/parallel.h"

namespace hdr4d::baselines::hexplane {

class PlainAdam {
 public:
  PlainAdam(float beta1, float beta2) : beta1_(beta1), beta2_(beta2) {}
  void Reset() {
    m_.clear();
    v_.clear();
    step_ = 0;
  }
  // The moments and step count, for a resumable checkpoint (hexplane_train_state.cpp); Read
  // throws naming `file` for a cut or foreign state.
  void Write(std::ostream& out) const {
    WritePod(out, std::int64_t(step_));
    WritePod(out, std::uint64_t(m_.size()));
    for (std::size_t k = 0; k < m_.size(); ++k) {
      WriteArray(out, m_[k]);
      WriteArray(out, v_[k]);
    }
  }
  void Read(std::istream& in, const std::string& file) {
    const auto step = ReadPod<std::int64_t>(in, file, "the optimiser's step");
    const auto slots = ReadPod<std::uint64_t>(in, file, "the optimiser's arrays");
    if (step < 0 || step > (std::int64_t{1} << 40) || slots > 64)
      Fail("{}: bad optimiser state (step {}, {} arrays)", file, step, slots);
    step_ = int(step);
    m_.assign(slots, {});
    v_.assign(slots, {});
    for (std::size_t k = 0; k < slots; ++k) {
      ReadArrayOfAnyLength(in, std::uint64_t{1} << 34, file, "an optimiser moment", &m_[k]);
      ReadArray(in, m_[k].size(), file, "an optimiser moment", &v_[k]);
    }
  }
  // Call once per iteration before the arrays' Update calls.
  void BeginStep() {
    ++step_;
    slot_ = 0;
  }
  void Update(std::vector<float>* params, const std::vector<float>& grads, float lr) {
    if (slot_ == m_.size()) {
      m_.emplace_back(params->size(), 0.0f);
      v_.emplace_back(params->size(), 0.0f);
    }
    if (m_[slot_].size() != params->size())  // a resumed state that does not fit the model
      Fail("hexplane: optimiser array {} has {} values, the parameters {}", slot_,
           m_[slot_].size(), params->size());
    std::vector<float>& m = m_[slot_];
    std::vector<float>& v = v_[slot_++];
    const float b1 = beta1_, b2 = beta2_;
    const float step_size = lr / (1.0f - std::pow(b1, float(step_)));
    const float inv_bias2 = 1.0f / std::sqrt(1.0f - std::pow(b2, float(step_)));
    float* p = params->data();
    const float* g = grads.data();
    ParallelForChunks(std::int64_t(params->size()), 1 << 16, [&](std::int64_t b, std::int64_t e) {
      for (std::int64_t i = b; i < e; ++i) {
        m[i] = b1 * m[i] + (1.0f - b1) * g[i];
        v[i] = b2 * v[i] + (1.0f - b2) * g[i] * g[i];
        p[i] -= step_size * m[i] / (std::sqrt(v[i]) * inv_bias2 + 1e-8f);
      }
    });
  }

 private:
  float beta1_, beta2_;
  int step_ = 0;
  std::size_t slot_ = 0;
  std::vector<std::vector<float>> m_, v_;
};

}  // namespace hdr4d::baselines::hexplane
