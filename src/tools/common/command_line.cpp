#include "occupancy_fusion/tools/command_line.h"

#include <cstdlib>
#include <limits>
#include <sstream>

namespace occupancy_fusion {

CommandLine::CommandLine(int argc, const char* const* argv,
                         const std::set<std::string>& value_options,
                         const std::set<std::string>& flags) {
  for (int i = 1; i < argc; ++i) {
    const std::string argument = argv[i];
    if (argument.rfind("--", 0) != 0 || argument.size() == 2) {
      throw UsageError("unexpected argument '" + argument + "'");
    }
    std::string name = argument.substr(2);
    std::string value;
    bool has_inline_value = false;
    const std::size_t equals = name.find('=');
    if (equals != std::string::npos) {
      value = name.substr(equals + 1);
      name = name.substr(0, equals);
      has_inline_value = true;
    }
    if (flags.count(name) > 0) {
      if (has_inline_value) throw UsageError("--" + name + " takes no value");
      values_[name].push_back("");
    } else if (value_options.count(name) > 0) {
      if (!has_inline_value) {
        if (i + 1 >= argc) throw UsageError("--" + name + " needs a value");
        value = argv[++i];
      }
      values_[name].push_back(value);
    } else {
      throw UsageError("unknown option '--" + name + "'");
    }
  }
}

std::string CommandLine::value(const std::string& name, const std::string& fallback) const {
  const auto entry = values_.find(name);
  return entry == values_.end() ? fallback : entry->second.back();
}

std::string CommandLine::required(const std::string& name) const {
  if (!has(name)) throw UsageError("missing --" + name);
  return value(name);
}

std::vector<std::string> CommandLine::values(const std::string& name) const {
  const auto entry = values_.find(name);
  return entry == values_.end() ? std::vector<std::string>{} : entry->second;
}

int CommandLine::intValue(const std::string& name, int fallback) const {
  if (!has(name)) return fallback;
  const std::string text = value(name);
  char* end = nullptr;
  const long parsed = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || parsed < std::numeric_limits<int>::min() ||
      parsed > std::numeric_limits<int>::max()) {
    throw UsageError("--" + name + " expects an integer, got '" + text + "'");
  }
  return static_cast<int>(parsed);
}

double CommandLine::doubleValue(const std::string& name, double fallback) const {
  if (!has(name)) return fallback;
  const std::string text = value(name);
  char* end = nullptr;
  const double parsed = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0') {
    throw UsageError("--" + name + " expects a number, got '" + text + "'");
  }
  return parsed;
}

std::vector<std::string> CommandLine::listValue(const std::string& name,
                                                const std::string& fallback) const {
  std::vector<std::string> items;
  std::stringstream stream(value(name, fallback));
  std::string item;
  while (std::getline(stream, item, ',')) {
    if (!item.empty()) items.push_back(item);
  }
  return items;
}

}  // namespace occupancy_fusion
