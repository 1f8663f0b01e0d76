// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "tools/unseen/commands.h"

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

namespace unseen::cli {
namespace {

std::vector<std::pair<std::string, CommandAdder>>& Registry() {
  static std::vector<std::pair<std::string, CommandAdder>> registry;
  return registry;
}

}  // namespace

bool RegisterCommand(const char* name, CommandAdder adder) {
  Registry().emplace_back(name, adder);
  return true;
}

void AddRegisteredCommands(CLI::App& app) {
  auto commands = Registry();
  std::sort(commands.begin(), commands.end());
  for (const auto& [name, adder] : commands) adder(app);
}

}  // namespace unseen::cli
