// linesurf: command-line front end. Parses arguments, calls the library, maps errors to exit
// codes: 0 ok, 1 usage or bad parameter, 2 bad input file, 3 other failure.
#include <cstdio>
#include <memory>

#include "command.h"
#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"

int main(int argc, char** argv) {
  using namespace linesurf;
  CLI::App app{"linesurf: surface modelling and rendering with line segments"};
  app.set_version_flag("--version", "linesurf 0.1.0");
  app.require_subcommand(1);
  app.fallthrough();  // global options (-q, -j) may follow the subcommand too
  auto& g = cli::globalOptions();
  app.add_flag("-q,--quiet", g.quiet, "No progress and no summary")->configurable(false);
  app.add_option("-j,--threads", g.threads, "Worker threads (0 = all cores)")->check(CLI::Range(0, 1024));
  for (auto& reg : cli::registeredCommands()) reg(app);
  // Thread limit must exist before any subcommand callback runs.
  std::unique_ptr<ThreadLimit> limit;
  app.parse_complete_callback([&] { limit = std::make_unique<ThreadLimit>(g.threads); });
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);  // prints help, version or the usage error
    return code == 0 ? 0 : 1;
  } catch (const Error& e) {
    cli::endProgress();
    std::fprintf(stderr, "%s\n", e.what());
    return e.kind() == Error::Kind::BadParameter ? 1 : 2;
  } catch (const std::bad_alloc&) {
    cli::endProgress();
    std::fprintf(stderr, "linesurf: out of memory\n");
    return 3;
  } catch (const std::exception& e) {
    cli::endProgress();
    std::fprintf(stderr, "linesurf: error: %s\n", e.what());
    return 3;
  }
  return 0;
}
