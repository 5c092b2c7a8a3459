// Camera response functions (CRFs): how a camera turns exposure-scaled linear irradiance
// x = radiance * exposure_time into a display value y in [0,1]. Used to synthesise LDR views
// from HDR renders (core/radiometry/ldr_synthesis.h), to linearise LDR images and to merge brackets.
//
// Conventions shared by every model:
// - Apply clamps x < 0 to 0 (sensor noise can push x below zero, and a hot path must not
//   throw); NaN propagates as NaN so a bug upstream stays visible; +inf saturates to 1.
// - Apply is monotonic non-decreasing, Apply(0) = 0, and Apply(x) = 1 for x >= Saturation().
// - Inverse(y) is the smallest x with Apply(x) >= y (y is clamped to [0,1]; NaN gives NaN), so
//   Inverse(0) = 0 and Inverse(1) = Saturation(). It throws hdr4d::Error unless Invertible().
// - Invertible() means every display value y in (0,1) comes from exactly one x: the curve has
//   no flat piece strictly between black and white. A flat toe at y = 0 (a black level, as
//   in a recovered response whose code 0 sits at x > 0) and the clip at y = 1 are allowed.
#pragma once

#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace hdr4d {

class Crf {
 public:
  virtual ~Crf() = default;
  // x >= 0 -> [0,1], monotonic non-decreasing, Apply(0) = 0.
  virtual double Apply(double x) const = 0;
  // The smallest x with Apply(x) = 1 (the clip point; 1 for the closed-form models).
  virtual double Saturation() const = 0;
  virtual bool Invertible() const = 0;
  // y in [0,1] -> x; throws hdr4d::Error if !Invertible().
  virtual double Inverse(double y) const = 0;
  // dApply/dx, x < 0 clamped to 0 as in Apply. The models override it with the analytic
  // derivative: the left derivative at a kink (so the slope just below the clip point at
  // x = Saturation()), the right one at x = 0, 0 above saturation, +inf where the slope is
  // unbounded (gamma > 1 at x = 0). This default is a finite difference for other models.
  virtual double Derivative(double x) const;
  // The string that recreates the curve with ParseCrf.
  virtual std::string Spec() const = 0;
  // {"model": ..., parameters...}; CrfFromJson reads it back.
  virtual nlohmann::json ToJson() const = 0;
};

// y = min(x, 1).
class LinearCrf final : public Crf {
 public:
  double Apply(double x) const override;
  double Saturation() const override { return 1.0; }
  bool Invertible() const override { return true; }
  double Inverse(double y) const override;
  double Derivative(double x) const override;
  std::string Spec() const override { return "linear"; }
  nlohmann::json ToJson() const override;
};

// y = min(x, 1)^(1/gamma), gamma > 0 and finite.
class GammaCrf final : public Crf {
 public:
  static constexpr double kDefaultGamma = 2.2;
  explicit GammaCrf(double gamma = kDefaultGamma);  // throws hdr4d::Error for a bad gamma
  double gamma() const { return gamma_; }
  double Apply(double x) const override;
  double Saturation() const override { return 1.0; }
  bool Invertible() const override { return true; }
  double Inverse(double y) const override;
  double Derivative(double x) const override;
  std::string Spec() const override;
  nlohmann::json ToJson() const override;

 private:
  double gamma_;
};

// The IEC 61966-2-1 sRGB encoding curve, evaluated in double precision. The standard's
// breakpoint (x = 0.0031308) leaves the two pieces 3e-8 apart, with the curve stepping *down*
// there; this model switches at the pieces' exact intersection (x = 0.00313066844250054)
// instead, which keeps it continuous and strictly increasing so the inverse is exact. It
// agrees with hdr4d::LinearToSrgb / SrgbToLinear (float) to within float rounding.
class SrgbCrf final : public Crf {
 public:
  static constexpr double kLinearEnd = 0.0031306684425005367;  // x where the pieces meet
  double Apply(double x) const override;
  double Saturation() const override { return 1.0; }
  bool Invertible() const override { return true; }
  double Inverse(double y) const override;
  double Derivative(double x) const override;
  std::string Spec() const override { return "srgb"; }
  nlohmann::json ToJson() const override;
};

// A filmic curve, a logistic function of log exposure, normalised to reach 1 at x = 1:
//   y = (1 + m^k) x^k / (x^k + m^k)  for x <= 1,  y = 1 above,
// with k = contrast > 0 and m = mid > 0. In u = ln x, x^k / (x^k + m^k) = sigmoid(k (u - ln m)),
// so dy/du peaks at x = m: an S-shape in log exposure with its steepest point at the mid
// (interior to (0, 1) when m < 1); k > 1 also gives a toe in linear x. Strictly increasing on
// [0, 1]; the inverse is closed-form: s = y / (1 + m^k), x = m (s / (1 - s))^(1/k).
class FilmicCrf final : public Crf {
 public:
  static constexpr double kDefaultContrast = 1.5;
  static constexpr double kDefaultMid = 0.18;
  FilmicCrf(double contrast = kDefaultContrast, double mid = kDefaultMid);  // throws hdr4d::Error
  double contrast() const { return k_; }
  double mid() const { return m_; }
  double Apply(double x) const override;
  double Saturation() const override { return 1.0; }
  bool Invertible() const override { return true; }
  double Inverse(double y) const override;
  double Derivative(double x) const override;
  std::string Spec() const override;
  nlohmann::json ToJson() const override;

 private:
  double k_, m_, mk_;  // mk_ = m^k
};

// A concave (Naka-Rushton / Michaelis-Menten) response on a gamma-encoded signal:
//   s = min(x, 1)^(1/gamma),   y = (1 + k) s / (s + k),
// with half-saturation k > 0 and gamma > 0: y(1) = 1. Its slope in log exposure falls from
// 1/gamma in the shadows towards 0 near white, so it compresses a very wide range into 8 bits
// (k = 0.2, gamma = 2.2 spans about 1e7:1 between code 1 and white). Inverse closed-form:
// s = k y / (1 + k - y), x = s^gamma.
class NakaRushtonCrf final : public Crf {
 public:
  NakaRushtonCrf(double half, double gamma);  // throws hdr4d::Error for bad parameters
  double half() const { return k_; }
  double gamma() const { return gamma_; }
  double Apply(double x) const override;
  double Saturation() const override { return 1.0; }
  bool Invertible() const override { return true; }
  double Inverse(double y) const override;
  double Derivative(double x) const override;
  std::string Spec() const override;
  nlohmann::json ToJson() const override;

 private:
  double k_, gamma_;
};

// Piecewise-linear through nodes (x_i, y_i), in the table's own units of x: its saturation is
// the first node with y = 1, not necessarily x = 1. Nodes must be finite, x >= 0 and strictly
// increasing, y non-decreasing within [0,1] and ending at y = 1; a first node with x > 0 gets
// (0, 0) prepended, a first node at x = 0 must have y = 0. Inverse: binary search + linear
// interpolation (exact for the piecewise-linear curve).
class TableCrf final : public Crf {
 public:
  // Throws hdr4d::Error naming `source` and the node for invalid nodes.
  TableCrf(std::vector<double> x, std::vector<double> y, std::string source);
  // An inverse response sampled per code, as Debevec-Malik recovery (and OpenCV's
  // CalibrateDebevec/Robertson) produce it: x_of_code[i] is the exposure of code i, and the
  // display value of code i is i / (N - 1). N >= 2.
  static std::unique_ptr<TableCrf> FromCodes(const std::vector<double>& x_of_code,
                                             std::string source);
  // Reads a CSV file ('#' comments and blank lines skipped; fields split by commas, or by
  // whitespace when a line has no comma; the first non-comment line may be a text header):
  // - two columns x,y: the nodes;
  // - one column of N >= 2 values (256 for an 8-bit camera): x per code, as FromCodes.
  // Errors name the file and the line.
  static std::unique_ptr<TableCrf> FromCsv(const std::string& path);

  const std::vector<double>& x() const { return x_; }
  const std::vector<double>& y() const { return y_; }
  double Apply(double x) const override;
  double Saturation() const override { return x_sat_; }
  bool Invertible() const override { return invertible_; }
  double Inverse(double y) const override;
  double Derivative(double x) const override;
  // "table:<source>": recreates the curve while the file is unchanged. ToJson embeds the
  // nodes, so the JSON form is self-contained.
  std::string Spec() const override { return "table:" + source_; }
  nlohmann::json ToJson() const override;

 private:
  std::vector<double> x_, y_;
  std::string source_;
  double x_sat_ = 1.0;
  bool invertible_ = true;
};

// "linear", "gamma" (2.2) or "gamma:<g>", "srgb", "filmic" (contrast 1.5, mid 0.18) or
// "filmic:<contrast>,<mid>", "naka-rushton:<k>,<gamma>", "table:<path.csv>" (see
// TableCrf::FromCsv). Throws hdr4d::Error
// naming the spec and what is wrong with it.
std::unique_ptr<Crf> ParseCrf(const std::string& spec);
// Reads Crf::ToJson output back; a table is rebuilt from its embedded "x"/"y" nodes, or
// from its "path" when those are absent. Throws hdr4d::Error naming the bad key.
std::unique_ptr<Crf> CrfFromJson(const nlohmann::json& json);

}  // namespace hdr4d
