// gtrack: one executable, one subcommand per job (see command.hpp).
#include <boost/program_options.hpp>
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include <fcntl.h>
#include <unistd.h>

#include "command.hpp"
#include "gtrack/config.hpp"
#include "gtrack/error.hpp"
#include "gtrack/log.hpp"
#include "gtrack/version.hpp"

namespace po = boost::program_options;
using gtrack::cli::Command;
using gtrack::cli::registry;

namespace gtrack::cli {
std::vector<Command>& registry() {
  static std::vector<Command> commands;
  return commands;
}
}  // namespace gtrack::cli

namespace {

bool g_stdout_closed = false;

po::options_description common_options() {
  po::options_description d("Common options");
  d.add_options()("help,h", "show this help")("version", "print the version and exit")(
      "log-level", po::value<std::string>()->default_value("info"),
      "trace, debug, info, warn, error, critical or off")(
      "plugin-path", po::value<std::vector<std::string>>()->composing(),
      "extra folder searched for plugins first (repeatable)");
  return d;
}

void print_version() {
  std::cout << "gtrack " << GTRACK_VERSION_STRING << " (plugin ABI " << GTRACK_PLUGIN_ABI_VERSION << ")\n";
}

void print_usage(std::ostream& os) {
  os << "gtrack " << GTRACK_VERSION_STRING
     << " - model-based tracking of untethered micro-grippers\n\n"
        "Usage: gtrack <command> [options]   (gtrack <command> --help for its options)\n\nCommands:\n";
  auto cmds = registry();
  std::sort(cmds.begin(), cmds.end(), [](const Command& a, const Command& b) { return a.name < b.name; });
  for (const auto& c : cmds) {
    os << "  " << c.name << std::string(c.name.size() < 10 ? 10 - c.name.size() : 1, ' ') << c.summary << "\n";
  }
  os << "\n" << common_options();
}

// The common options that take a value may also come before the command
// (`gtrack --log-level debug plugins`): they are moved after it.
std::vector<char*> command_first(int argc, char** argv) {
  std::vector<std::string> valued;  // "--name" of each common option with a value
  const po::options_description common = common_options();
  for (const auto& o : common.options()) {
    if (o->semantic()->max_tokens() > 0) valued.push_back("--" + o->long_name());
  }
  const auto is_valued = [&](const std::string& a) {
    return std::find(valued.begin(), valued.end(), a) != valued.end();
  };
  std::vector<char*> leading;
  int i = 1;
  for (; i < argc; ++i) {
    const std::string a = argv[i];
    const bool with_value = is_valued(a);
    const size_t eq = a.find('=');
    const bool joined = eq != std::string::npos && is_valued(a.substr(0, eq));
    if (with_value && i + 1 < argc) {
      leading.push_back(argv[i]);
      leading.push_back(argv[++i]);
    } else if (joined) {
      leading.push_back(argv[i]);
    } else {
      break;
    }
  }
  std::vector<char*> out{argv[0]};
  if (i < argc) out.push_back(argv[i++]);
  out.insert(out.end(), leading.begin(), leading.end());
  for (; i < argc; ++i) out.push_back(argv[i]);
  return out;
}

int run(int argc, char** argv) {
  if (argc < 2) {
    print_usage(std::cerr);
    return 2;
  }
  const std::string first = argv[1];
  if (first == "--version") {
    print_version();
    return 0;
  }
  if (first == "--help" || first == "-h" || first == "help") {
    print_usage(std::cout);
    return 0;
  }
  const Command* cmd = nullptr;
  for (const auto& c : registry()) {
    if (c.name == first) cmd = &c;
  }
  if (!cmd) {
    std::vector<std::string> names;
    for (const auto& c : registry()) names.push_back(c.name);
    std::string msg = "gtrack: error: unknown command '" + gtrack::shown(first) + "'";
    if (auto m = gtrack::closest_match(first, names)) msg += " (did you mean '" + *m + "'?)";
    std::cerr << msg << "; run 'gtrack --help' for the list\n";
    return 2;
  }

  po::options_description own("Options of 'gtrack " + cmd->name + "'");
  if (cmd->declare) cmd->declare(own);
  po::options_description all;
  all.add(own).add(common_options());
  po::positional_options_description pos;
  for (const auto& p : cmd->positional) pos.add(p.c_str(), 1);
  po::variables_map vm;
  try {
    po::store(po::command_line_parser(argc - 1, argv + 1).options(all).positional(pos).run(), vm);
    if (vm.count("help")) {
      std::cout << "gtrack " << cmd->name << ": " << cmd->summary << "\n\n" << all;
      return 0;
    }
    if (vm.count("version")) {
      print_version();
      return 0;
    }
    // Every required option missing, in the order --help lists them (the
    // parser names only one).
    std::string missing;
    for (const auto& o : own.options()) {
      if (o->semantic()->is_required() && !vm.count(o->long_name())) {
        missing += (missing.empty() ? "--" : ", --") + o->long_name();
      }
    }
    if (!missing.empty()) {
      std::cerr << "gtrack: error: missing " << missing << " (see 'gtrack " << cmd->name << " --help')\n";
      return 2;
    }
    po::notify(vm);
  } catch (const po::error& e) {
    std::cerr << "gtrack: error: " << gtrack::shown(e.what()) << " (see 'gtrack " << cmd->name << " --help')\n";
    return 2;
  }

  gtrack::cli::CommonOptions common;
  common.log_level = vm["log-level"].as<std::string>();
  common.stdout_closed = g_stdout_closed;
  try {
    gtrack::set_log_level(common.log_level);
  } catch (const gtrack::Error& e) {
    throw gtrack::cli::UsageError(e.what());
  }
  if (vm.count("plugin-path")) {
    for (const auto& p : vm["plugin-path"].as<std::vector<std::string>>()) common.plugin_paths.emplace_back(p);
  }
  return cmd->run(common, vm);
}

}  // namespace

int main(int argc, char** argv) {
  // A standard stream the caller closed (`gtrack ... >&-`) is /dev/null:
  // otherwise the first file opened would take its number, and what is
  // printed would be written into it.
  for (int fd = 0; fd <= 2; ++fd) {
    if (::fcntl(fd, F_GETFD) != -1) continue;
    if (::open("/dev/null", fd == 0 ? O_RDONLY : O_WRONLY) != fd) return 1;
    if (fd == STDOUT_FILENO) g_stdout_closed = true;
  }
  try {
    std::vector<char*> args = command_first(argc, argv);
    return run(static_cast<int>(args.size()), args.data());
  } catch (const gtrack::cli::UsageError& e) {
    std::cerr << "gtrack: error: " << gtrack::shown(e.what()) << "\n";
    return 2;
  } catch (const gtrack::Error& e) {
    std::cerr << "gtrack: error: " << gtrack::shown(e.what()) << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "gtrack: error: " << gtrack::shown(gtrack::library_words(e.what())) << "\n";
    return 1;
  } catch (...) {
    // Only a plugin's code throws anything else; the calls gtrack makes to
    // plugins name them, this is the last resort.
    std::cerr << "gtrack: error: something that is not a std::exception was thrown (by a plugin's code)\n";
    return 1;
  }
}
