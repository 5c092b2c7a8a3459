// A batch of rays through a HexPlane model, forward and backward: samples along each ray in the
// box that the occupancy grid keeps, densities from the density planes, compositing weights,
// then the appearance (planes, basis, MLP) only where a sample's weight passes the reference's
// threshold, and the composite. The rays are split into lanes, one per thread, each with its own
// gradient buffers (summed at the end), so the result does not depend on scheduling.
//
// Output per ray: the LDR colour (3) for an LDR model; for log-HDR colours the LDR colour of
// HDR-HexPlane's sigmoid tone mapper (baselines/sigmoid_tone_mapper.h) on ln radiance +
// ln exposure + the image's offset, then the HDR radiance exp(ln radiance) (6 values), both
// composited per sample with the same weights, as the reference.
#pragma once

#include <memory>
#include <vector>

#include "baselines/hexplane/hexplane_model.h"

namespace hdr4d::baselines::hexplane {

struct Ray {
  float origin[3];
  float dir[3];  // unit length
  float time;    // in [-1, 1]
  float log_exposure = 0;
  int image = -1;  // training image (its exposure offset), or -1
};

// Channels a ray renders to: 3 (LDR model) or 6 (LDR then HDR).
int RayChannels(const HexPlaneModel& m);

class RayBatch {
 public:
  RayBatch();
  ~RayBatch();
  // jitter: one value in [0, 1) per sample position along the rays (NumSamples()), shifting
  // every ray's samples by that fraction of the spacing (the reference's training jitter); null
  // for fixed samples. With jitter (training), a few samples per ray below the weight threshold
  // get their colour too (kExploreSamples, ray_batch_lane.h). The model must stay unchanged
  // until Backward.
  void Forward(const HexPlaneModel& m, const std::vector<Ray>& rays, const float* jitter,
               std::vector<float>* out);
  // The last Forward's rays again at other exposures (`rays` as they were but for log_exposure
  // and image): only the tone mapper, the background and the composite are redone, so the
  // brackets of one view cost one march and one appearance. Exactly Forward's output on `rays`
  // (without jitter); for an LDR model (no exposure input) the same output as before.
  void Reexpose(const HexPlaneModel& m, const std::vector<Ray>& rays, std::vector<float>* out);
  // dL_dout: RayChannels per ray. Overwrites *grads with the batch's gradient.
  void Backward(const HexPlaneModel& m, const std::vector<float>& dL_dout, HexPlaneGrads* grads);
  // Samples whose density and whose appearance were evaluated in the last Forward.
  std::int64_t density_samples() const;
  std::int64_t app_samples() const;

 private:
  struct Lane;
  std::vector<std::unique_ptr<Lane>> lanes_;
  const std::vector<Ray>* rays_ = nullptr;
};

}  // namespace hdr4d::baselines::hexplane
