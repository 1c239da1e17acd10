#include "command.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <mutex>

namespace linesurf::cli {

GlobalOptions& globalOptions() {
  static GlobalOptions options;
  return options;
}

namespace {
std::vector<std::pair<int, Registrar>>& registry() {
  static std::vector<std::pair<int, Registrar>> r;
  return r;
}
std::mutex progressMutex;
bool progressLineOpen = false;
}  // namespace

RegisterCommand::RegisterCommand(int order, Registrar r) { registry().emplace_back(order, std::move(r)); }

std::vector<Registrar> registeredCommands() {
  auto r = registry();
  std::stable_sort(r.begin(), r.end(), [](auto& a, auto& b) { return a.first < b.first; });
  std::vector<Registrar> out;
  for (auto& [order, f] : r) out.push_back(f);
  return out;
}

CLI::App* extractCommand(CLI::App& app) {
  auto found = app.get_subcommands([](CLI::App* s) { return s->get_name() == "extract"; });
  if (!found.empty()) return found.front();
  return app.add_subcommand("extract", "Extract a line-segment or hybrid model")->require_subcommand(1);
}

ProgressFn progressBar() {
  if (globalOptions().quiet || !isatty(STDERR_FILENO)) return {};
  auto last = std::make_shared<std::chrono::steady_clock::time_point>();
  return [last](std::string_view stage, double fraction) {
    std::lock_guard<std::mutex> lock(progressMutex);
    auto now = std::chrono::steady_clock::now();
    if (fraction < 1.0 && now - *last < std::chrono::milliseconds(100)) return;
    *last = now;
    fraction = std::clamp(fraction, 0.0, 1.0);
    const int width = 30;
    int filled = int(fraction * width + 0.5);
    std::string bar(size_t(filled), '#');
    bar.resize(width, '.');
    std::fprintf(stderr, "\r%-24.24s [%s] %3d%%", std::string(stage).c_str(), bar.c_str(), int(fraction * 100 + 0.5));
    std::fflush(stderr);
    progressLineOpen = true;
  };
}

void endProgress() {
  std::lock_guard<std::mutex> lock(progressMutex);
  if (progressLineOpen) {
    std::fprintf(stderr, "\r%*s\r", 70, "");
    std::fflush(stderr);
    progressLineOpen = false;
  }
}

void say(const std::string& line) {
  if (globalOptions().quiet) return;
  endProgress();
  std::fputs(line.c_str(), stdout);
  std::fputc('\n', stdout);
}

}  // namespace linesurf::cli
