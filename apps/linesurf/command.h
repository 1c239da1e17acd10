#pragma once
// Subcommand registry of the linesurf CLI. Each apps/linesurf/cmd_*.cpp registers its
// subcommand with a static RegisterCommand, so adding a command touches no other file.
#include <CLI/CLI.hpp>

#include <functional>
#include <string>
#include <vector>

#include "linesurf/core/progress.h"

namespace linesurf::cli {

/// Options common to every subcommand (set by the top-level parser before the callback runs).
struct GlobalOptions {
  bool quiet = false;
  int threads = 0;  ///< 0 = all cores
};
GlobalOptions& globalOptions();

/// Adds one subcommand to `app`; the subcommand's callback does the work.
using Registrar = std::function<void(CLI::App& app)>;
struct RegisterCommand {
  RegisterCommand(int order, Registrar r);
};
/// Registered subcommands sorted by `order` (the order they appear in --help).
std::vector<Registrar> registeredCommands();

/// The `extract` parent command shared by the three extraction methods (created on first use).
CLI::App* extractCommand(CLI::App& app);

/// A progress callback that draws a bar on stderr when it is a terminal and --quiet is off.
ProgressFn progressBar();
/// Ends the progress line (call before printing a summary).
void endProgress();

/// Prints to stdout unless --quiet.
void say(const std::string& line);

}  // namespace linesurf::cli
