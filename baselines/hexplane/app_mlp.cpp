#include "baselines/hexplane/app_mlp.h"

#include "baselines/hexplane/dense_simd.h"

namespace hdr4d::baselines::hexplane {

std::vector<float> InitAppMlp(const AppMlpShape& shape, std::uint64_t seed) {
  const method::MlpShape layers = shape.Layers();
  std::vector<float> p(layers.NumParams());
  method::MlpInit(layers, seed, p.data());
  for (int k = 1; k <= layers.outputs(); ++k) p[p.size() - k] = 0.0f;  // zero_init of the last bias
  return p;
}

void AppMlpForward(const method::MlpShape& shape, const float* params, const RowMatrix<float>& x,
                   std::vector<RowMatrix<float>>* acts) {
  acts->resize(shape.layers());
  const float* p = params;
  const int rows = int(x.rows());
  std::vector<float> wt;  // W transposed: in x out, the product's row-major right operand
  for (int l = 0; l < shape.layers(); ++l) {
    const int ni = shape.widths[l], no = shape.widths[l + 1];
    const float* b = p + std::size_t(no) * ni;
    wt.resize(std::size_t(ni) * no);
    for (int o = 0; o < no; ++o)
      for (int i = 0; i < ni; ++i) wt[std::size_t(i) * no + o] = p[std::size_t(o) * ni + i];
    const RowMatrix<float>& in = l == 0 ? x : (*acts)[l - 1];
    RowMatrix<float>& out = (*acts)[l];
    out.resize(rows, no);
    for (int r = 0; r < rows; ++r) std::copy(b, b + no, out.row(r).data());
    DenseProduct(rows, no, ni, in.data(), ni, 1, wt.data(), no, out.data(), no, true);
    if (l + 1 < shape.layers()) {
      out = out.cwiseMax(0.0f);
    } else if (shape.output == method::MlpOutput::kSigmoid) {
      out = out.unaryExpr([](float z) { return StableSigmoid(z); });
    }
    p += std::size_t(no) * (ni + 1);
  }
}

void AppMlpBackward(const method::MlpShape& shape, const float* params, const RowMatrix<float>& x,
                    const std::vector<RowMatrix<float>>& acts, const RowMatrix<float>& dL_dout,
                    float* dL_dparams, RowMatrix<float>* dL_dx) {
  const int L = shape.layers(), rows = int(x.rows());
  RowMatrix<float> dz = dL_dout, din;
  if (shape.output == method::MlpOutput::kSigmoid)
    dz = dz.cwiseProduct(acts[L - 1].unaryExpr([](float y) { return y * (1.0f - y); }));
  std::size_t poff = shape.NumParams();
  for (int l = L - 1; l >= 0; --l) {
    const int ni = shape.widths[l], no = shape.widths[l + 1];
    poff -= std::size_t(no) * (ni + 1);
    const float* W = params + poff;
    float* dW = dL_dparams + poff;
    Eigen::Map<Eigen::Matrix<float, 1, Eigen::Dynamic>> db(dW + std::size_t(no) * ni, no);
    const RowMatrix<float>& in = l == 0 ? x : acts[l - 1];
    // dW += dz^T in: A(o, r) = dz(r, o).
    DenseProduct(no, ni, rows, dz.data(), 1, no, in.data(), ni, dW, ni, true);
    db += dz.colwise().sum();
    if (l == 0 && !dL_dx) break;
    din.resize(rows, ni);
    DenseProduct(rows, ni, no, dz.data(), no, 1, W, ni, din.data(), ni, false);
    if (l == 0) {
      *dL_dx = std::move(din);
    } else {
      // Through the ReLU below: its output is 0 where it cut.
      dz = din.cwiseProduct(in.unaryExpr([](float a) { return a > 0.0f ? 1.0f : 0.0f; }));
    }
  }
}

}  // namespace hdr4d::baselines::hexplane
