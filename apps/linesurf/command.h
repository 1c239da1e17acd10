#pragma once
// Subcommand registry of the linesurf CLI. Each apps/linesurf/cmd_*.cpp registers its
// subcommand with a static RegisterCommand, so adding a command touches no other file.
#include <CLI/CLI.hpp>

#include <functional>
#include <initializer_list>
#include <string>
#include <vector>

#include "linesurf/core/budget.h"
#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "linesurf/core/progress.h"
#include "linesurf/io/atomic_file.h"

namespace linesurf::cli {

/// Options common to every subcommand (set by the top-level parser before the callback runs).
struct GlobalOptions {
  bool quiet = false;
  int threads = 0;  ///< 0 = all cores
  double maxMegabytes = 4096;  ///< --max-mb: largest image buffer or output estimated before work
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

/// Checks a command's file arguments before any work (main.cpp's OutputTransaction checks the
/// files actually written again), and that reading each input fits the budget. Throws Error:
/// - BadParameter (exit 1): an output equal to an input (same file, or same path), two outputs
///   with one path, an output whose extension is not one of `extensions` (e.g. {".png"});
/// - Io (exit 3): an output whose folder does not exist, or an output that is a folder.
/// `outputs` pairs an option name (as typed, for messages) with its value; empty values are
/// skipped (except for the main output, "--output"/"output"). An input path that does not exist
/// is left to the reader.
struct OutputSpec {
  std::string option, path;
  std::vector<std::string> extensions;  ///< lower case with the dot; empty = any
};
/// inputsHeldWhole: reading an input holds it in memory (checked against the budget); false for
/// commands that estimate their own path first (normals, the extractions: in memory or out of core).
void checkFiles(const std::vector<std::string>& inputs, const std::vector<OutputSpec>& outputs,
                bool inputsHeldWhole = true);

/// The command's budget (--max-mb): every output and the working memory, estimated before the work.
Budget budget();

/// Runs `work`; a library error that blames one of the named arguments (what an algorithm refuses
/// in the data: a non-finite point, coincident points, no normals) is the file's fault, rethrown
/// as BadInput naming the file that argument came from. Option errors pass as they are.
template <typename F>
auto blamingFiles(std::initializer_list<std::pair<const char*, std::string>> files, F&& work) -> decltype(work()) {
  try {
    return work();
  } catch (const OptionError&) {
    throw;
  } catch (const Error& e) {
    for (const auto& [argument, path] : files)
      if (e.path() == argument) throw Error(Error::Kind::BadInput, path, e.where(), e.reason());
    throw;
  }
}
/// Refuses (BadParameter, exit 1) work whose estimated size exceeds --max-mb, naming `option`.
void checkSize(const std::string& option, double bytes, const std::string& what);

/// Refuses a model output (.ply binary, .xyz / ASCII text by extension) over the budget.
void checkModelOutput(const std::string& option, const std::string& path, size_t points, size_t segments);
/// Refuses the §6.1 geometry of `points` points over the budget, naming the input.
void checkGeometry(const std::string& input, size_t points, int k);

/// The command's output transaction (opened by main.cpp): setOutputTransaction registers it,
/// commitOutputs() renames what was written so far into place before the command ends (for a
/// batch such as `experiment` that reports failed models but keeps the others' results).
void setOutputTransaction(OutputTransaction* t);
void commitOutputs();

/// Prints to stdout unless --quiet.
void say(const std::string& line);

}  // namespace linesurf::cli
