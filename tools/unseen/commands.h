// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// The subcommands of the `unseen` binary, one file each. A file defines a function that
// adds its subcommand to the app and registers it with UNSEEN_REGISTER_COMMAND; main()
// adds every registered subcommand in name order. Callbacks throw unseen::Error on bad
// input, which main() reports as "unseen: error: ..." with exit code 1.
#pragma once

#include <CLI/CLI.hpp>

namespace unseen::cli {

using CommandAdder = void (*)(CLI::App& app);

// Records a subcommand; returns true so it can initialise a static.
bool RegisterCommand(const char* name, CommandAdder adder);
// Adds every registered subcommand to `app`, sorted by name.
void AddRegisteredCommands(CLI::App& app);

// Adds --obj-id to a command that opens a sequence: which object of a scene of several
// (a BOP scene's scene_gt.json lists each) it is about; Sequence::Open's `obj_id`.
void AddObjectIdOption(CLI::App* cmd, int* obj_id);

}  // namespace unseen::cli

#define UNSEEN_REGISTER_COMMAND(name, adder) \
  [[maybe_unused]] static const bool kRegistered_##adder = \
      ::unseen::cli::RegisterCommand(name, adder)
