// Fuzz target: the data-defined gripper format (plugin "data_defined").
//
// The input is a TOML document; its [gripper] table (or the root when there is
// none) is handed to the plugin's factory exactly as PluginLoader would hand
// it, then the loader's unused-key check runs. A gripper that is accepted must
// then be usable: it is posed, its endpoints and K(H) computed, its symmetric
// equivalents taken. Only gtrack::Error may come out.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string_view>
#include <vector>

#include "gtrack/config.hpp"
#include "gtrack/error.hpp"
#include "toml_known_bugs.hpp"
#include "gtrack/gripper.hpp"

// The plugin's factory, compiled into this executable (see fuzz/CMakeLists.txt)
// instead of loaded with dlopen, so that it is instrumented with the rest.
namespace gtrack_plugin_detail {
gtrack::Gripper* create(const gtrack::ConfigTable& table);
}

namespace {

void exercise(const gtrack::ArticulatedModel& m) {
  Eigen::VectorXd h = Eigen::VectorXd::Zero(m.dims());
  h[2] = 100;
  h[3] = 20;
  h[5] = 30;
  for (int f = 0; f < m.fingers(); ++f) h[gtrack::kPoseDims + f] = 10.0 * f;
  std::vector<Eigen::Vector3d> out;
  m.pose(h, out);
  if (out.size() != m.mesh().size()) __builtin_trap();
  (void)m.link_endpoints(h);
  (void)m.fingertips(h);
  std::vector<double> joints(h.data() + gtrack::kPoseDims, h.data() + h.size());
  (void)m.kinematic_penalty(joints);
  (void)m.radius_mm();
  for (int k = 0; k < m.geometry().symmetry_order && k < 8; ++k) (void)m.symmetric_equivalent(h, k);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  if (gtrack_fuzz::has_toml_unreachable_code_point(text)) return 0;
  try {
    const auto root = gtrack::ConfigTable::parse(text, "fuzz.toml");
    const gtrack::ConfigTable table = root.has("gripper") ? root.table("gripper") : root;
    // model_file would read another file: not outside input of this target.
    if (table.has("model_file")) return 0;
    table.mark_used("plugin");
    std::unique_ptr<gtrack::Gripper> g(gtrack_plugin_detail::create(table));
    table.check_all_used();
    exercise(g->model());
    std::vector<double> joints(static_cast<size_t>(g->model().fingers()), 45.0);
    (void)g->kinematic_penalty(joints);
  } catch (const gtrack::Error&) {
  }
  return 0;
}
