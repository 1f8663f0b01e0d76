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

void AddObjectIdOption(CLI::App* cmd, int* obj_id) {
  cmd->add_option("--obj-id", *obj_id,
                  "Object of a scene of several, by its BOP obj_id (default: sequence.json's "
                  "object, else the first in the ground truth); its model is "
                  "models/obj_<id>.* unless --model gives one")
      ->check(CLI::PositiveNumber);
}

}  // namespace unseen::cli
