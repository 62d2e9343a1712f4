// Writing a plugin: one macro, GTRACK_PLUGIN, in one source file.
//
//     class MySensor : public gtrack::Sensor { public: explicit MySensor(const gtrack::ConfigTable&); ... };
//     GTRACK_PLUGIN(MySensor, gtrack::Sensor, "my_sensor", "1.0.0", "what it is")
//
// The macro checks at compile time that the class implements the interface
// and is constructible from a ConfigTable and, when built with
// gtrack_add_plugin, that the name and the interface are the target's NAME
// and KIND (gtrack finds a plugin by its file, libgtrack_NAME.so), and exports through Boost.DLL
// aliases a PluginInfo record and a factory. The loader reads PluginInfo and
// compares the ABI version, the record's size and alignment, and the kind,
// before it calls anything in the library.
#pragma once

#include <boost/dll/alias.hpp>
#include <cstdint>
#include <string_view>
#include <type_traits>

#include "gtrack/config.hpp"
#include "gtrack/gripper.hpp"
#include "gtrack/sensor.hpp"
#include "gtrack/stimulus.hpp"
#include "gtrack/version.hpp"

namespace gtrack {

enum class PluginKind : std::uint32_t { Sensor = 1, Gripper = 2, Stimulus = 3 };

// Laid out so that abi_version, info_size and info_align can be read from a
// plugin built against any version.
struct PluginInfo {
  std::uint32_t abi_version;
  std::uint32_t info_size;
  std::uint32_t info_align;
  PluginKind kind;
  const char* name;
  const char* version;
  const char* summary;
};

template <class Interface>
struct PluginTraits;
template <>
struct PluginTraits<Sensor> {
  static constexpr PluginKind kind = PluginKind::Sensor;
};
template <>
struct PluginTraits<Gripper> {
  static constexpr PluginKind kind = PluginKind::Gripper;
};
template <>
struct PluginTraits<Stimulus> {
  static constexpr PluginKind kind = PluginKind::Stimulus;
};


// The factory every plugin exports: returns a new instance owned by the caller.
template <class Interface>
using PluginFactory = Interface*(const ConfigTable&);

namespace plugin_detail {
// What gtrack_add_plugin says the library is (nothing when built otherwise).
#ifdef GTRACK_PLUGIN_TARGET
static constexpr std::string_view kTargetName = GTRACK_PLUGIN_TARGET;
#else
static constexpr std::string_view kTargetName = {};
#endif
#if defined(GTRACK_PLUGIN_KIND_sensor)
static constexpr PluginKind kTargetKind = PluginKind::Sensor;
#elif defined(GTRACK_PLUGIN_KIND_gripper)
static constexpr PluginKind kTargetKind = PluginKind::Gripper;
#elif defined(GTRACK_PLUGIN_KIND_stimulus)
static constexpr PluginKind kTargetKind = PluginKind::Stimulus;
#else
static constexpr PluginKind kTargetKind{0};
#endif
// libstdc++'s string ABI is gtrack's (GTRACK_CXX11_ABI comes with the
// gtrack::framework target; unknown when the target is not linked).
#if defined(GTRACK_CXX11_ABI) && defined(_GLIBCXX_USE_CXX11_ABI)
static constexpr bool kSameStringAbi = (GTRACK_CXX11_ABI != 0) == (_GLIBCXX_USE_CXX11_ABI != 0);
#else
static constexpr bool kSameStringAbi = true;
#endif
}  // namespace plugin_detail

inline const char* to_string(PluginKind kind) {
  switch (kind) {
    case PluginKind::Sensor: return "sensor";
    case PluginKind::Gripper: return "gripper";
    case PluginKind::Stimulus: return "stimulus";
  }
  return "unknown";
}

}  // namespace gtrack

#define GTRACK_PLUGIN(Class, Interface, Name, Version, Summary)                                      \
  static_assert(std::is_base_of_v<Interface, Class>,                                                 \
                "GTRACK_PLUGIN: " #Class " must derive from " #Interface);                           \
  static_assert(!std::is_abstract_v<Class>,                                                          \
                "GTRACK_PLUGIN: " #Class " does not implement every pure virtual of " #Interface);   \
  /* an abstract class is never constructible: the line above says why */                          \
  static_assert(std::is_abstract_v<Class> || std::is_constructible_v<Class, const ::gtrack::ConfigTable&>, \
                "GTRACK_PLUGIN: " #Class " needs a constructor taking const gtrack::ConfigTable&");  \
  static_assert(::gtrack::plugin_detail::kTargetName.empty() ||                                      \
                    ::gtrack::plugin_detail::kTargetName == std::string_view(Name),                  \
                "GTRACK_PLUGIN: the name must be the NAME given to gtrack_add_plugin: gtrack finds " \
                "the plugin by its file, libgtrack_NAME.so");                                        \
  static_assert(::gtrack::plugin_detail::kTargetKind == ::gtrack::PluginKind{0} ||                   \
                    ::gtrack::plugin_detail::kTargetKind == ::gtrack::PluginTraits<Interface>::kind, \
                "GTRACK_PLUGIN: " #Interface " is not the KIND given to gtrack_add_plugin");        \
  static_assert(::gtrack::plugin_detail::kSameStringAbi,                                            \
                "GTRACK_PLUGIN: built with another _GLIBCXX_USE_CXX11_ABI than gtrack: std::string "   \
                "differs between the two and the plugin would crash at its first call; build it "     \
                "(and the libraries it links) without -D_GLIBCXX_USE_CXX11_ABI=0");                   \
  namespace gtrack_plugin_detail {                                                                   \
  const ::gtrack::PluginInfo plugin_info{GTRACK_PLUGIN_ABI_VERSION,                                  \
                                         sizeof(::gtrack::PluginInfo),                               \
                                         alignof(::gtrack::PluginInfo),                              \
                                         ::gtrack::PluginTraits<Interface>::kind,                    \
                                         Name,                                                       \
                                         Version,                                                    \
                                         Summary};                                                   \
  Interface* create(const ::gtrack::ConfigTable& table) { return new Class(table); }                 \
  }                                                                                                  \
  BOOST_DLL_ALIAS(gtrack_plugin_detail::plugin_info, gtrack_plugin_info)                             \
  BOOST_DLL_ALIAS(gtrack_plugin_detail::create, gtrack_plugin_create)
