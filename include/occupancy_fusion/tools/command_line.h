// A small long-option parser for the tools: "--name value", "--name=value", repeatable options
// and flags. Anything it does not know is a UsageError, which the tools report with exit code 2.
#pragma once

#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace occupancy_fusion {

// A wrong command line (unknown option, missing or malformed value, missing file). The tools
// print the message and their usage and exit with kUsageExitCode.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

constexpr int kUsageExitCode = 2;

class CommandLine {
 public:
  // value_options take a value; flags do not. Names are given without the leading "--".
  // Throws UsageError on unknown options, positional arguments and options without value.
  CommandLine(int argc, const char* const* argv, const std::set<std::string>& value_options,
              const std::set<std::string>& flags);

  bool has(const std::string& name) const { return values_.count(name) > 0; }
  // The last value given, or fallback when the option is absent.
  std::string value(const std::string& name, const std::string& fallback = "") const;
  // The value; UsageError "missing --name" when absent.
  std::string required(const std::string& name) const;
  // Every value given, in order (for repeatable options such as --set).
  std::vector<std::string> values(const std::string& name) const;
  // The value (or fallback) as a comma-separated list, empty items left out: "a,b" -> {a, b}.
  std::vector<std::string> listValue(const std::string& name, const std::string& fallback) const;
  // Parsed numbers; UsageError naming the option when the text is not a number of that kind.
  int intValue(const std::string& name, int fallback) const;
  double doubleValue(const std::string& name, double fallback) const;

 private:
  std::map<std::string, std::vector<std::string>> values_;
};

}  // namespace occupancy_fusion
