// gtrack plugins: one line per plugin found (kind, name, version, file, summary).
#include <algorithm>
#include <iostream>

#include "command.hpp"
#include "gtrack/config.hpp"
#include "gtrack/plugin_loader.hpp"
#include "gtrack/setup.hpp"

namespace {

int run_plugins(const gtrack::cli::CommonOptions& common, const boost::program_options::variables_map& vm) {
  gtrack::PluginLoader loader(common.plugin_paths);
  // A config's plugin_path too, searched after --plugin-path, as track
  // searches it: what that config would find.
  if (vm.count("config")) {
    const auto root = gtrack::ConfigTable::load_file(vm["config"].as<std::string>());
    for (const auto& dir : gtrack::config_plugin_paths(root)) loader.add_path(dir);
  }
  if (vm.count("paths")) {  // the folders alone: no plugin is opened
    for (const auto& p : loader.search_paths()) std::cout << p.string() << "\n";
    return 0;
  }
  auto records = loader.discover();
  // Sensors, then grippers, then stimuli, each kind in the order found.
  std::stable_sort(records.begin(), records.end(), [](const auto& a, const auto& b) { return a.kind < b.kind; });
  if (records.empty()) {
    std::string where;
    for (const auto& p : loader.search_paths()) where += (where.empty() ? "" : ", ") + p.string();
    std::cerr << "gtrack: error: no plugins found in: " << where << "\n";
    return 1;
  }
  for (const auto& r : records) {
    // The summary last: a script that takes the first four fields still can.
    // A tab or a line break of the plugin's own would split the line.
    std::string summary = r.summary;
    std::replace_if(summary.begin(), summary.end(), [](char c) { return c == '\t' || c == '\n' || c == '\r'; }, ' ');
    std::cout << gtrack::to_string(r.kind) << "\t" << r.name << "\t" << r.version << "\t" << r.file.string() << "\t"
              << summary << "\n";
  }
  // The first file of a name is the one taken: copies further down the
  // search path (another build, an older install) are said, on stderr.
  for (const auto& r : records) {
    for (const auto& other : loader.set_aside_by(r.file)) {
      std::cerr << "note: " << other.string() << " is set aside: " << r.file.string() << " is found first\n";
    }
  }
  return 0;
}

}  // namespace

GTRACK_COMMAND("plugins", "list the plugins found: kind, name, version, file, what it is",
               [](boost::program_options::options_description& d) {
                 d.add_options()("config,c", boost::program_options::value<std::string>(),
                                 "also search the folders this config's plugin_path names, as track does")(
                     "paths", "print the folders searched, in order, instead");
               },
               run_plugins)
