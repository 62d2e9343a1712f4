// PluginLoader: search, ABI check before any call, construction, lifetime.
#include "gtrack/plugin_loader.hpp"

#include <boost/dll/runtime_symbol_info.hpp>
#include <boost/dll/shared_library.hpp>
#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <type_traits>

#include "gtrack/error.hpp"
#include "gtrack/log.hpp"
#include "checked_stimulus.hpp"

namespace gtrack {

namespace fs = std::filesystem;
namespace dll = boost::dll;

namespace {

// A plugin name is part of a file name, libgtrack_<name>.so: letters,
// digits, '_' and '-', 1 to 64 of them.
bool is_plugin_name(const std::string& name) {
  return !name.empty() && name.size() <= 64 && std::all_of(name.begin(), name.end(), [](unsigned char c) {
           return std::isalnum(c) || c == '_' || c == '-';
         });
}
// Guards every loader's list of the plugins it made.
std::mutex& loaded_mutex() {
  static std::mutex mutex;
  return mutex;
}

const std::string kPrefix = "libgtrack_";
const std::string kSuffix = ".so";

// The folder of libgtrack.so itself: right for the gtrack executable, the
// tests and any program that links the framework, installed or not.
fs::path library_dir() { return framework_library_file().parent_path(); }

fs::path prefix_dir() {
  fs::path p = library_dir();
  for (const auto& part : fs::path(GTRACK_LIBDIR)) {
    (void)part;
    p = p.parent_path();
  }
  return p;
}

std::string library_file_name(const std::string& name) { return kPrefix + name + kSuffix; }

std::shared_ptr<dll::shared_library> open_library(const fs::path& file) {
  try {
    return std::make_shared<dll::shared_library>(file, dll::load_mode::rtld_now | dll::load_mode::rtld_local);
  } catch (const std::exception& e) {
    std::string why = e.what();
    // Boost wraps dlerror's text; keep only that part.
    if (auto p = why.find("dlerror system message: "); p != std::string::npos) {
      why = why.substr(p + 24);
      if (auto q = why.rfind("): "); q != std::string::npos) why = why.substr(0, q);
    }
    throw PluginError(file.string() + ": cannot load library: " + why);
  }
}

// Reads and checks PluginInfo. Only reads data: no function of the library
// runs before this has passed.
PluginRecord check_info(const dll::shared_library& lib, const fs::path& file) {
  // Both symbols are aliases: variables that hold a pointer. A null one
  // would be dereferenced by get_alias, so each is read as data first.
  for (const char* symbol : {"gtrack_plugin_info", "gtrack_plugin_create"}) {
    if (!lib.has(symbol)) {
      throw PluginError(file.string() + ": not a gtrack plugin (it exports no " + symbol +
                        "; was it built with GTRACK_PLUGIN?)");
    }
    if (lib.get<const void* const>(symbol) == nullptr) {
      throw PluginError(file.string() + ": not a gtrack plugin (its " + symbol + " is a null pointer)");
    }
  }
  const auto& head = lib.get_alias<const std::uint32_t>("gtrack_plugin_info");
  const std::uint32_t* words = &head;
  if (words[0] != GTRACK_PLUGIN_ABI_VERSION) {
    throw PluginError(file.string() + ": plugin ABI version " + std::to_string(words[0]) +
                      " does not match this gtrack's plugin ABI version " +
                      std::to_string(GTRACK_PLUGIN_ABI_VERSION) + "; rebuild the plugin against this gtrack");
  }
  if (words[1] != sizeof(PluginInfo) || words[2] != alignof(PluginInfo)) {
    throw PluginError(file.string() + ": plugin info record has size " + std::to_string(words[1]) + " and alignment " +
                      std::to_string(words[2]) + ", expected " + std::to_string(sizeof(PluginInfo)) + " and " +
                      std::to_string(alignof(PluginInfo)) + "; rebuild the plugin against this gtrack");
  }
  const auto& info = lib.get_alias<const PluginInfo>("gtrack_plugin_info");
  if (info.kind != PluginKind::Sensor && info.kind != PluginKind::Gripper && info.kind != PluginKind::Stimulus) {
    throw PluginError(file.string() + ": plugin declares an unknown kind (" +
                      std::to_string(static_cast<std::uint32_t>(info.kind)) + ")");
  }
  if (!info.name || !*info.name) throw PluginError(file.string() + ": plugin has no name");
  return PluginRecord{info.kind, info.name, info.version ? info.version : "", info.summary ? info.summary : "", file};
}

std::string join_paths(const std::vector<fs::path>& paths) {
  std::string s;
  for (const auto& p : paths) s += (s.empty() ? "" : ", ") + p.string();
  return s.empty() ? "(none)" : s;
}

}  // namespace

fs::path executable_dir() {
  std::error_code ec;
  return dll::program_location(ec).parent_path();
}
fs::path default_plugin_dir() { return library_dir() / "gtrack" / "plugins"; }
fs::path data_dir() {
  if (const char* env = std::getenv("GTRACK_DATA_DIR"); env && *env) return env;
  return prefix_dir() / "share" / "gtrack";
}

namespace {

// A folder named for plugins that is not there is most likely a typo: said
// once per folder, and the search goes on without it.
void warn_if_missing(const fs::path& dir, const char* from) {
  static std::set<std::string> warned;
  std::error_code ec;
  if (!fs::is_directory(dir, ec) && warned.insert(dir.string()).second) {
    const bool exists = fs::exists(dir, ec);
    logger().warn("plugin folder {} ({}) {}", dir.string(), from,
                  exists ? "is not a folder (plugins are found in folders, not named as files)" : "does not exist");
  }
}

}  // namespace

std::string plugin_label(PluginKind kind, const std::string& name, const fs::path& file) {
  return std::string(to_string(kind)) + " plugin '" + name + "' (" + file.string() + ")";
}

PluginLoader::PluginLoader(std::vector<fs::path> user_paths) : initial_user_(std::move(user_paths)) {
  for (const auto& p : initial_user_) warn_if_missing(p, "--plugin-path");
  if (const char* env = std::getenv("GTRACK_PLUGIN_PATH"); env && *env) {
    std::string s = env;
    size_t start = 0;
    while (start <= s.size()) {
      size_t colon = s.find(':', start);
      if (colon == std::string::npos) colon = s.size();
      if (colon > start) {
        env_paths_.emplace_back(s.substr(start, colon - start));
        warn_if_missing(env_paths_.back(), "GTRACK_PLUGIN_PATH");
      }
      start = colon + 1;
    }
  }
  rebuild();
}

void PluginLoader::add_path(const fs::path& dir) {
  warn_if_missing(dir, "plugin_path");
  user_.push_back(dir);
  rebuild();
}

void PluginLoader::rebuild() {
  // user paths given at construction keep their place before later additions
  std::vector<fs::path> all;
  for (const auto& p : initial_user_) all.push_back(p);
  for (const auto& p : user_) all.push_back(p);
  for (const auto& p : env_paths_) all.push_back(p);
  all.push_back(default_plugin_dir());
  // A folder named twice (GTRACK_PLUGIN_PATH set to the built-in folder,
  // say) is searched, and shown in messages, once: at its first place.
  paths_.clear();
  for (const auto& p : all) {
    const auto same = [&](const fs::path& q) {
      std::error_code ec;
      return q == p || fs::equivalent(q, p, ec);
    };
    if (std::none_of(paths_.begin(), paths_.end(), same)) paths_.push_back(p);
  }
}

// A library that made an instance stays loaded until the process exits. An
// exception thrown by a plugin's method can be of a type whose destructor
// and vtable are the plugin's own copies (gtrack::Error's are inline): the
// last instance can go while the stack unwinds, and the catch block that
// then destroys the exception must still find that code mapped.
namespace {
void keep_loaded(const std::shared_ptr<dll::shared_library>& lib, const fs::path& file) {
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<dll::shared_library>> loaded;
  const std::lock_guard<std::mutex> lock(mutex);
  loaded.try_emplace(file.string(), lib);
}
}  // namespace

PluginRecord PluginLoader::inspect(const fs::path& file) {
  auto lib = open_library(file);
  return check_info(*lib, file);
}

std::vector<PluginRecord> PluginLoader::discover() const {
  std::vector<PluginRecord> out;
  std::map<std::string, bool> seen;
  // Files skipped, by file name: a run looking for that name takes the
  // skipped one, not a good one of the same name further down the path.
  std::map<std::string, fs::path> skipped;
  const auto listed = [&](PluginRecord r, const fs::path& file) {
    const std::string key = std::string(to_string(r.kind)) + "/" + r.name;
    if (seen[key]) return;
    seen[key] = true;
    if (const auto it = skipped.find(file.filename().string()); it != skipped.end()) {
      logger().warn("{} plugin '{}' is listed from {}, but a run takes {} ahead of it, and fails; remove or rename "
                    "that file",
                    to_string(r.kind), r.name, file.string(), it->second.string());
    }
    out.push_back(std::move(r));
  };
  for (const auto& dir : paths_) {
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) continue;
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(dir, ec)) {
      const std::string n = e.path().filename().string();
      if (n.size() > kPrefix.size() + kSuffix.size() && n.rfind(kPrefix, 0) == 0 &&
          n.compare(n.size() - kSuffix.size(), kSuffix.size(), kSuffix) == 0) {
        files.push_back(e.path());
      }
    }
    std::sort(files.begin(), files.end());
    for (const auto& f : files) {
      try {
        PluginRecord r = inspect(f);
        // Found by its file, a plugin named otherwise could never be loaded.
        if (f.filename().string() != library_file_name(r.name)) {
          logger().warn("skipping {}: it declares the {} plugin '{}', which gtrack looks for as {}; rename the file "
                        "or the name in GTRACK_PLUGIN",
                        f.string(), to_string(r.kind), r.name, library_file_name(r.name));
          skipped.try_emplace(f.filename().string(), f);
          continue;
        }
        listed(std::move(r), f);
      } catch (const PluginError& e) {
        logger().warn("skipping {}", e.what());
        skipped.try_emplace(f.filename().string(), f);
      }
    }
  }
  return out;
}

std::vector<fs::path> PluginLoader::set_aside_by(const fs::path& taken) const {
  std::vector<fs::path> out;
  std::error_code ec;
  auto dir = std::find_if(paths_.begin(), paths_.end(),
                          [&](const fs::path& d) { return fs::equivalent(d, taken.parent_path(), ec); });
  if (dir == paths_.end()) return out;
  for (++dir; dir != paths_.end(); ++dir) {
    const fs::path other = *dir / taken.filename();
    if (fs::exists(other, ec) && !fs::equivalent(other, taken, ec) && !ec) out.push_back(other);
  }
  return out;
}

fs::path PluginLoader::find(PluginKind kind, const std::string& name) const {
  // (make() has checked that the name is a file name part, never a path.)
  for (const auto& dir : paths_) {
    fs::path f = dir / library_file_name(name);
    std::error_code ec;
    if (!fs::exists(f, ec)) continue;
    // A plugin of the same name further down the search path (a built-in
    // one, say) is set aside: said, since the run then differs from one
    // without the folder.
    if (const auto aside = set_aside_by(f); !aside.empty()) {
      static std::mutex mutex;
      static std::set<fs::path> said;  // once a file: a replayed stimulus is made again each frame
      const std::lock_guard<std::mutex> lock(mutex);
      if (said.insert(f).second) {
        logger().info("{} plugin '{}' taken from {}, ahead of the one in {}", to_string(kind), name, f.string(),
                      aside.front().parent_path().string());
      }
    }
    return f;
  }
  std::string known;
  for (const auto& r : discover()) {
    if (r.kind == kind) known += (known.empty() ? "" : ", ") + r.name;
  }
  std::string msg = std::string(to_string(kind)) + " plugin '" + name + "' not found (looked for " +
                    library_file_name(name) + " in: " + join_paths(paths_) + ")";
  msg += known.empty() ? std::string("; no ") + to_string(kind) + " plugins were found there"
                       : std::string("; available ") + to_string(kind) + " plugins: " + known;
  // A library of that name without the prefix (built with add_library
  // instead of gtrack_add_plugin): said, as the likely cause.
  for (const auto& dir : paths_) {
    for (const std::string& other : {"lib" + name + ".so", name + ".so"}) {
      std::error_code ec;
      if (fs::is_regular_file(dir / other, ec)) {
        msg += "; " + (dir / other).string() + " is there, but a plugin's file is named " + library_file_name(name) +
               " (gtrack_add_plugin names it so)";
        throw PluginError(msg);
      }
    }
  }
  throw PluginError(msg);
}

template <class Interface>
std::shared_ptr<Interface> PluginLoader::make_from_file(const fs::path& file, const std::string& name,
                                                        const ConfigTable& table) const {
  constexpr PluginKind kind = PluginTraits<Interface>::kind;
  auto lib = open_library(file);
  PluginRecord rec = check_info(*lib, file);
  if (rec.kind != kind) {
    throw PluginError(file.string() + ": plugin '" + rec.name + "' is a " + to_string(rec.kind) + " plugin; [" +
                      table.path() + "] needs a " + to_string(kind) + " plugin");
  }
  if (rec.name != name) {
    throw PluginError(file.string() + ": the library declares the plugin name '" + rec.name + "', expected '" + name +
                      "'");
  }
  auto& factory = lib->get_alias<PluginFactory<Interface>>("gtrack_plugin_create");
  Interface* raw = nullptr;
  // The plugin's exception must be caught while its library is loaded.
  try {
    raw = factory(table);
  } catch (const ConfigError& e) {
    throw ConfigError(e.what());
  } catch (const std::exception& e) {
    throw PluginError(plugin_label(kind, name, file) + ": could not be created: " + e.what());
  } catch (...) {
    throw PluginError(plugin_label(kind, name, file) +
                      ": could not be created: its constructor threw something that is not a std::exception");
  }
  if (!raw) {
    throw PluginError(plugin_label(kind, name, file) + ": factory returned nothing");
  }
  // The deleter owns the library as well (keep_loaded's hold ends with the
  // process's static objects): the instance is destroyed while its code is
  // still mapped, whenever that is.
  std::shared_ptr<Interface> instance(raw, [lib](Interface* p) { delete p; });
  keep_loaded(lib, file);
  table.check_all_used();
  {
    const std::lock_guard<std::mutex> lock(loaded_mutex());
    rec.file = file;
    const bool known = std::any_of(loaded_->begin(), loaded_->end(), [&](const PluginRecord& r) {
      return r.kind == rec.kind && r.name == rec.name && r.file == rec.file;
    });
    if (!known) loaded_->push_back(rec);
  }
  logger().debug("loaded {} plugin '{}' {} from {}", to_string(kind), rec.name, rec.version, file.string());
  // A stimulus's results are checked as the tracker takes them.
  if constexpr (std::is_same_v<Interface, Stimulus>) {
    return std::make_shared<detail::CheckedStimulus>(instance, plugin_label(kind, name, file));
  }
  return instance;
}

template <class Interface>
std::shared_ptr<Interface> PluginLoader::make(const ConfigTable& table) const {
  constexpr PluginKind kind = PluginTraits<Interface>::kind;
  if (!table.has("plugin")) {
    table.fail("plugin", std::string("missing; [") + table.path() + "] must name a " + to_string(kind) + " plugin" +
                             table.misspelling_hint("plugin"));
  }
  const std::string name = table.string("plugin");
  if (!is_plugin_name(name)) {
    // A file given for its name: the name is the file's less "libgtrack_"
    // and ".so", and its folder goes in plugin_path.
    const bool file = name.find('/') != std::string::npos || name.find(".so") != std::string::npos;
    table.fail("plugin", "expected a plugin name (letters, digits, '_' and '-', 1 to 64 characters), got '" +
                             shown(name, 60) + "'" +
                             (file ? "; a plugin is named without its folder or file name ('light' for "
                                     "libgtrack_light.so), its folder given in plugin_path or --plugin-path"
                                   : ""));
  }
  // Where the config names the plugin, ahead of what is wrong with it (not
  // found, not loadable, another kind or ABI, its factory failed).
  try {
    return make_from_file<Interface>(find(kind, name), name, table);
  } catch (const PluginError& e) {
    throw PluginError(table.where("plugin") + ": " + e.what());
  }
}

fs::path framework_library_file() {
  static const fs::path file = [] {
    std::error_code ec;
    fs::path p = dll::this_line_location(ec);
    if (ec) p = dll::program_location(ec);
    return fs::weakly_canonical(p);
  }();
  return file;
}

std::vector<PluginRecord> PluginLoader::loaded() const {
  const std::lock_guard<std::mutex> lock(loaded_mutex());
  return *loaded_;
}

std::shared_ptr<Sensor> PluginLoader::make_sensor(const ConfigTable& t) const { return make<Sensor>(t); }
std::shared_ptr<Gripper> PluginLoader::make_gripper(const ConfigTable& t) const { return make<Gripper>(t); }
std::shared_ptr<Stimulus> PluginLoader::make_stimulus(const ConfigTable& t) const { return make<Stimulus>(t); }

template GTRACK_API std::shared_ptr<Sensor> PluginLoader::make_from_file<Sensor>(const fs::path&, const std::string&,
                                                                                 const ConfigTable&) const;
template GTRACK_API std::shared_ptr<Gripper> PluginLoader::make_from_file<Gripper>(const fs::path&, const std::string&,
                                                                                   const ConfigTable&) const;
template GTRACK_API std::shared_ptr<Stimulus> PluginLoader::make_from_file<Stimulus>(const fs::path&,
                                                                                     const std::string&,
                                                                                     const ConfigTable&) const;

}  // namespace gtrack
