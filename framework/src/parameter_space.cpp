// Bounds of the hypothesis vector and parsing of "x,y,z,rx,ry,rz,q1,...".
#include "gtrack/parameter_space.hpp"

#include <charconv>
#include <cmath>
#include <string>

#include "gtrack/error.hpp"

namespace gtrack {

void ParameterSpace::clamp(Eigen::Ref<Eigen::VectorXd> h) const {
  const int boxed = position_box && h.size() >= 3 ? 3 : 0;  // x, y, z go to the box below
  for (int i = 0; i < boxed; ++i) {
    if (!std::isfinite(h[i])) h[i] = 0.5 * (lower[i] + upper[i]);
  }
  for (int i = boxed; i < dims(); ++i) {
    double& v = h[i];
    if (!std::isfinite(v)) v = 0.5 * (lower[i] + upper[i]);
    if (periodic[i]) {
      const double span = upper[i] - lower[i];
      v = lower[i] + std::fmod(std::fmod(v - lower[i], span) + span, span);
    } else {
      v = std::min(std::max(v, lower[i]), upper[i]);
    }
  }
  if (boxed) {
    // The nearest point of the turned box, then within the bounds for the
    // turn's rounding (the bounds hold the box).
    const PositionBox& b = *position_box;
    const Eigen::Vector3d q = b.to_box(h.head<3>()).cwiseMax(b.lower).cwiseMin(b.upper);
    h.head<3>() = b.from_box(q).cwiseMax(lower.head<3>()).cwiseMin(upper.head<3>());
  }
}

bool ParameterSpace::contains(const Eigen::Ref<const Eigen::VectorXd>& h) const {
  if (h.size() != dims()) return false;
  for (int i = 0; i < dims(); ++i) {
    if (!std::isfinite(h[i])) return false;
    if (!periodic[i] && (h[i] < lower[i] || h[i] > upper[i])) return false;
  }
  if (position_box && h.size() >= 3) {
    const PositionBox& b = *position_box;
    const Eigen::Vector3d q = b.to_box(h.head<3>());
    constexpr double kSlack = 1e-9;  // mm: the turn's rounding
    if (((q - b.lower).array() < -kSlack).any() || ((q - b.upper).array() > kSlack).any()) return false;
  }
  return true;
}

ParameterSpace ParameterSpace::make(int fingers, const Eigen::Vector3d& pos_lo, const Eigen::Vector3d& pos_hi,
                                    const Eigen::Vector3d& rot_lo, const Eigen::Vector3d& rot_hi, double joint_lo,
                                    double joint_hi, bool rz_periodic) {
  ParameterSpace s;
  const int d = kPoseDims + fingers;
  for (int i = 0; i < d; ++i) s.names.push_back(parameter_name(i));
  s.lower.resize(d);
  s.upper.resize(d);
  s.lower << pos_lo, rot_lo, Eigen::VectorXd::Constant(fingers, joint_lo);
  s.upper << pos_hi, rot_hi, Eigen::VectorXd::Constant(fingers, joint_hi);
  s.periodic.assign(d, false);
  s.periodic[5] = rz_periodic;
  return s;
}

Eigen::VectorXd parse_parameter_vector(std::string_view text, int expected_dims) {
  std::vector<double> values;
  size_t pos = 0;
  int field = 0;
  while (pos <= text.size()) {
    size_t comma = text.find(',', pos);
    if (comma == std::string_view::npos) comma = text.size();
    std::string_view item = text.substr(pos, comma - pos);
    ++field;
    while (!item.empty() && std::isspace(static_cast<unsigned char>(item.front()))) item.remove_prefix(1);
    while (!item.empty() && std::isspace(static_cast<unsigned char>(item.back()))) item.remove_suffix(1);
    double v = 0;
    auto [end, ec] = std::from_chars(item.data(), item.data() + item.size(), v);
    if (item.empty() || ec != std::errc() || end != item.data() + item.size() || !std::isfinite(v)) {
      throw InputError("parameter vector: field " + std::to_string(field) + " ('" + std::string(item) +
                       "') is not a finite number; expected " + std::to_string(expected_dims) +
                       " comma-separated values x,y,z (mm), rx,ry,rz (deg), q1..qF (deg)");
    }
    values.push_back(v);
    pos = comma + 1;
    if (comma == text.size()) break;
  }
  if (static_cast<int>(values.size()) != expected_dims) {
    throw InputError("parameter vector: got " + std::to_string(values.size()) + " values, expected " +
                     std::to_string(expected_dims) + " (x,y,z in mm, rx,ry,rz in deg, then " +
                     std::to_string(expected_dims - kPoseDims) + " joint values in deg)");
  }
  return Eigen::Map<Eigen::VectorXd>(values.data(), expected_dims);
}

std::string joint_name(int finger) { return "q" + std::to_string(finger) + "_deg"; }

std::string parameter_name(int d) {
  static const char* const pose[kPoseDims] = {"x_mm", "y_mm", "z_mm", "rx_deg", "ry_deg", "rz_deg"};
  return d < kPoseDims ? pose[d] : joint_name(d - kPoseDims + 1);
}

}  // namespace gtrack
