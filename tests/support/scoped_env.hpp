// An environment variable set for a scope, and restored after.
#pragma once

#include <cstdlib>
#include <optional>
#include <string>

namespace gtrack::testing {

class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    ::setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() {
    if (old_) {
      ::setenv(name_, old_->c_str(), 1);
    } else {
      ::unsetenv(name_);
    }
  }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

  // The value before the scope, if the variable was set.
  const std::optional<std::string>& old() const { return old_; }

 private:
  const char* name_;
  std::optional<std::string> old_;
};

// A gtrack run that starts the gl backend goes without LeakSanitizer's
// check: Mesa's driver is unloaded before the check runs at exit, and its
// allocations then show as leaks that no suppression can name (as for the
// gl tests in scripts/ci_sanitize.sh). Without the sanitizers the option is
// not read.
inline std::string asan_options_without_leak_check() {
  const char* old = std::getenv("ASAN_OPTIONS");
  return (old ? std::string(old) + ":" : std::string()) + "detect_leaks=0";
}

}  // namespace gtrack::testing
