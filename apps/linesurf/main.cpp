// linesurf: command-line front end. Parses arguments, calls the library, maps errors to exit
// codes: 0 ok, 1 usage or bad parameter, 2 bad input file, 3 failure to write and other failures.
// Every error is one line on stderr ("PATH: WHERE: WHAT"). Every command runs inside one
// OutputTransaction: its outputs are renamed into place only when the whole command succeeded.
#include <signal.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <new>

#include <fmt/format.h>

#include "command.h"
#include "ooc_cli.h"
#include "options_bind.h"
#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "linesurf/core/parallel.h"
#include "linesurf/io/atomic_file.h"

namespace {
void printError(const std::string& message) {
  linesurf::cli::endProgress();
  // The errors that reach here come before the ranks split the work (the out-of-core path's own
  // are reported by the rank that meets them): every rank meets the same one, and rank 0 says it.
  if (linesurf::cli::launchedRank() != 0) return;
  std::fprintf(stderr, "%s\n", linesurf::oneLine(message).c_str());
}
}  // namespace

int main(int argc, char** argv) {
  using namespace linesurf;
  // An interrupted command removes its temporary outputs and dies by its signal; a file-size
  // limit (ulimit -f) is a failed write (exit 3), not a killed process.
  installCleanupOnSignals();
  ::signal(SIGXFSZ, SIG_IGN);
  CLI::App app{"linesurf: surface modelling and rendering with line segments"};
  app.set_version_flag("--version", "linesurf 0.1.0");
  app.require_subcommand(1);
  app.fallthrough();  // global options (-q, -j) may follow the subcommand too
  auto& g = cli::globalOptions();
  app.add_flag("-q,--quiet", g.quiet, "No progress and no summary")->configurable(false);
  // Read as every table option is (options_bind.h): NaN or a non-number is refused naming the flag.
  app.add_option_function<std::string>("-j,--threads", [&g](const std::string& t) {
        const OptionSpec spec{"threads", "", closedRange(0, 1024)};
        g.threads = cli::parseNumber<int>(spec, t);
        requireRange(spec.name, g.threads, 0, 1024, "(0 = all cores)");
      }, "Worker threads (0 = all cores), [0, 1024]")
      ->type_name("INT");
  app.add_option_function<std::string>("--max-mb", [&g](const std::string& t) {
        const OptionSpec spec{"maxMb", "", closedRange(1, 1e9)};
        g.maxMegabytes = cli::parseNumber<double>(spec, t);
        requireRange(spec.name, g.maxMegabytes, 1, 1e9, "MiB");
      }, "Memory and output budget, MiB: the largest image, buffer or output a command may make (estimated before "
         "the work), and the memory beyond which normals, the point extractions and lod build go out of core and "
         "size their tiles (out of core: the process's peak resident set, refused up front when too small), [1, 1e9]")
      ->type_name("MiB")
      ->default_str(fmt::format("{}", g.maxMegabytes));
  for (auto& reg : cli::registeredCommands()) reg(app);
  // Thread limit must exist before any subcommand callback runs.
  std::unique_ptr<ThreadLimit> limit;
  app.parse_complete_callback([&] {
    cli::budget();  // refuses a --max-mb that is NaN (the range check lets NaN through)
    limit = std::make_unique<ThreadLimit>(g.threads);
  });
  try {
    OutputTransaction outputs;
    cli::setOutputTransaction(&outputs);
    app.parse(argc, argv);
    cli::setOutputTransaction(nullptr);
    outputs.commit();
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    // CLI11's ExistingFile / ExistingDirectory checks: a missing input is a bad input (2).
    const std::string what = e.what();
    for (const char* key : {"File does not exist: ", "Directory does not exist: ", "Path does not exist: "})
      if (size_t at = what.find(key); at != std::string::npos) {
        printError(what.substr(at + std::strlen(key)) + ": no such " + (key[0] == 'D' ? "folder" : "file"));
        return 2;
      }
    if (app.get_subcommands().empty() && argc > 1 && argv[1][0] != '-') {
      printError(std::string("linesurf: unknown command '") + argv[1] + "' (see --help)");
      return 1;
    }
    printError(std::string("linesurf: ") + e.what() + " (see --help)");
    return 1;
  } catch (const OptionError& e) {
    printError(cliMessage(e));  // names the flags as typed
    return 1;
  } catch (const Error& e) {
    printError(e.what());
    switch (e.kind()) {
      case Error::Kind::BadParameter: return 1;
      case Error::Kind::BadInput: return 2;
      case Error::Kind::Io: return 3;
    }
    return 3;
  } catch (const std::bad_alloc&) {
    printError("linesurf: out of memory (a smaller --size, spacing or model needs less)");
    return 3;
  } catch (const std::filesystem::filesystem_error& e) {
    printError(e.path1().string() + ": " + e.code().message());
    return 3;
  } catch (const std::exception& e) {
    printError(std::string("linesurf: error: ") + e.what());
    return 3;
  }
  return 0;
}
