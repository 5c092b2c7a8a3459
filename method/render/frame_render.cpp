#include "method/render/frame_render.h"

#include <vector>

#include "core/util/error.h"
#include "method/raster/binning.h"
#include "method/raster/blend.h"

namespace hdr4d::method {
namespace {

RasterSettings SettingsFor(const Camera& camera, const RenderOptions& options, int channels) {
  RasterSettings settings;
  settings.width = camera.intrinsics.width;
  settings.height = camera.intrinsics.height;
  settings.background =
      options.background.empty() ? std::vector<float>(channels, 0.0f) : options.background;
  settings.backend = options.backend;
  settings.keep_records = options.backward_follows;
  settings.share_image = options.track_max_weight ? options.share_image : nullptr;
  return settings;
}

// The backward keeps the largest blending weights only when asked (they cost a max per pixel
// vector and a value per tile entry).
template <typename T>
void TrackMaxWeight(const RenderOptions& options, std::size_t n, SplatGradientsT<T>* grads) {
  if (options.track_max_weight) {
    grads->max_weight.assign(n, T(0));
  } else {
    grads->max_weight.clear();
  }
}

}  // namespace

void RenderForward(const GaussianModel& model,
                   const Camera& camera,
                   float time,
                   const RenderOptions& options,
                   FrameState* state,
                   float* image) {
  const ViewParams<float> view = ViewParams<float>::FromCamera(camera);
  PreprocessForward(model, view, time, options, state);
  RasterSettings settings = SettingsFor(camera, options, state->splats.channels);
  if (BackgroundSource* source = options.background_source) {
    source->Forward(state->splats.channels, &state->background);
    settings.background = state->background;
  }
  RasterizeForward(state->splats, settings, &state->raster, image);
}

void RenderBackward(const GaussianModel& model,
                    const Camera& camera,
                    float time,
                    const RenderOptions& options,
                    FrameState* state,
                    const float* dL_dimage,
                    GaussianGradients* grads,
                    const GradientRowsDone& rows_done,
                    const float* dL_dimage_geometry) {
  const int features = state->splats.channels;
  state->splat_grads.SetZero(model.size(), features);
  TrackMaxWeight(options, model.size(), &state->splat_grads);
  RasterSettings settings = SettingsFor(camera, options, features);
  float* dL_dbackground = nullptr;
  if (options.background_source) {
    settings.background = state->background;  // what the forward blended
    state->background_grad.assign(features, 0.0f);
    dL_dbackground = state->background_grad.data();
  }
  BlendBackward(state->splats, settings, &state->raster, dL_dimage, nullptr, &state->splat_grads,
                dL_dbackground, dL_dimage_geometry);
  if (BackgroundSource* source = options.background_source)
    source->Backward(features, state->background_grad.data());
  if (ColorStage* stage = options.color_stage) {
    state->color_grads.resize(model.size() * model.channels);
    stage->Backward(state->colors.data(), model.channels, state->visible,
                    state->splat_grads.features.data(), state->color_grads.data());
  }
  if (grads == nullptr) return;
  PreprocessBackward(model, ViewParams<float>::FromCamera(camera), time, options, *state, grads,
                     rows_done);
}

template <typename T>
void RenderForwardReference(const GaussianModelT<T>& model,
                            const Camera& camera,
                            T time,
                            const RenderOptions& options,
                            FrameStateT<T>* state,
                            T* image) {
  const ViewParams<T> view = ViewParams<T>::FromCamera(camera);
  PreprocessForwardReference(model, view, time, options, state);
  const RasterSettings settings = SettingsFor(camera, options, model.channels);
  BinSplats(state->splats, settings, &state->raster);
  const std::vector<T> background(settings.background.begin(), settings.background.end());
  const std::size_t pixels = static_cast<std::size_t>(settings.width) * settings.height;
  state->final_T.resize(pixels);
  state->n_contrib.resize(pixels);
  BlendForwardReference(state->splats, state->raster, background.data(), image,
                        state->final_T.data(), state->n_contrib.data());
}

template <typename T>
void RenderBackwardReference(const GaussianModelT<T>& model,
                             const Camera& camera,
                             T time,
                             const RenderOptions& options,
                             FrameStateT<T>* state,
                             const T* dL_dimage,
                             GaussianGradientsT<T>* grads) {
  const RasterSettings settings = SettingsFor(camera, options, model.channels);
  HDR4D_CHECK(settings.share_image == nullptr);  // the blend's own tests cover the share
  const std::vector<T> background(settings.background.begin(), settings.background.end());
  state->splat_grads.SetZero(model.size(), model.channels);
  TrackMaxWeight(options, model.size(), &state->splat_grads);
  BlendBackwardReference(state->splats, state->raster, background.data(), state->final_T.data(),
                         state->n_contrib.data(), dL_dimage, static_cast<const T*>(nullptr),
                         &state->splat_grads, static_cast<T*>(nullptr));
  PreprocessBackwardReference(model, ViewParams<T>::FromCamera(camera), time, options, *state,
                              grads);
}

#define HDR4D_INSTANTIATE_RENDER(T)                                                      \
  template void RenderForwardReference(const GaussianModelT<T>&, const Camera&, T,       \
                                       const RenderOptions&, FrameStateT<T>*, T*);       \
  template void RenderBackwardReference(const GaussianModelT<T>&, const Camera&, T,      \
                                        const RenderOptions&, FrameStateT<T>*, const T*, \
                                        GaussianGradientsT<T>*);
HDR4D_INSTANTIATE_RENDER(float)
HDR4D_INSTANTIATE_RENDER(double)
#undef HDR4D_INSTANTIATE_RENDER

}  // namespace hdr4d::method
