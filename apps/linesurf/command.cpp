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

#include <fmt/format.h>

#include <filesystem>

#include "linesurf/core/error.h"
#include "linesurf/io/atomic_file.h"

namespace linesurf::cli {

namespace {
std::filesystem::path canonicalOrSelf(const std::string& p) {
  std::error_code ec;
  auto c = std::filesystem::weakly_canonical(std::filesystem::absolute(p, ec), ec);
  return ec ? std::filesystem::path(p).lexically_normal() : c;
}
std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}
}  // namespace

void checkFiles(const std::vector<std::string>& inputs, const std::vector<OutputSpec>& outputs, bool inputsHeldWhole) {
  // Reading holds at least the file's bytes and what they decode to.
  for (const std::string& in : inputsHeldWhole ? inputs : std::vector<std::string>{}) {
    std::error_code ec;
    if (in.empty() || !std::filesystem::is_regular_file(in, ec)) continue;
    const auto bytes = std::filesystem::file_size(in, ec);
    if (!ec) checkSize(in, 2.0 * double(bytes), "reading it");
  }
  std::vector<std::pair<std::filesystem::path, const OutputSpec*>> seen;
  for (const OutputSpec& o : outputs) {
    if (o.path.empty()) {
      // An optional output not asked for; the main output typed as '' is refused.
      if (o.option == "--output" || o.option == "output") throwBadParameter(o.option, "empty path");
      continue;
    }
    const std::string where = o.option + " " + o.path;
    const FileId id = fileId(o.path);
    const std::filesystem::path c = canonicalOrSelf(o.path);
    for (const std::string& in : inputs) {
      if (in.empty()) continue;
      if ((id.exists() && id == fileId(in)) || c == canonicalOrSelf(in))
        throwBadParameter(o.option, fmt::format("'{}' is also the input '{}' (not overwritten)", o.path, in));
    }
    if (!o.extensions.empty()) {
      const std::string ext = lower(std::filesystem::path(o.path).extension().string());
      bool ok = false;
      std::string list;
      for (const std::string& e : o.extensions) {
        ok = ok || ext == e;
        list += (list.empty() ? "" : ", ") + e;
      }
      if (!ok)
        throwBadParameter(o.option, fmt::format("'{}': the extension must be {} (the format written)", o.path, list));
    }
    for (auto& [p, other] : seen)
      if (p == c) throwBadParameter(o.option, fmt::format("'{}' is also the path of {}", o.path, other->option));
    seen.emplace_back(c, &o);
    std::filesystem::path dir = std::filesystem::path(o.path).parent_path();
    if (dir.empty()) dir = ".";
    std::error_code ec;
    if (!std::filesystem::is_directory(dir, ec)) throwIo(o.path, "output folder does not exist");
    if (std::filesystem::is_directory(o.path, ec)) throwIo(o.path, "is a directory");
    if (::access(dir.c_str(), W_OK) != 0) throwIo(o.path, "output folder is not writable");
  }
}

namespace {
OutputTransaction* currentTransaction = nullptr;
}
void setOutputTransaction(OutputTransaction* t) { currentTransaction = t; }
void commitOutputs() {
  if (currentTransaction) currentTransaction->commit();
}

Budget budget() { return Budget(globalOptions().maxMegabytes, "--max-mb"); }

void checkSize(const std::string& option, double bytes, const std::string& what) { budget().require(option, bytes, what); }

void checkModelOutput(const std::string& option, const std::string& path, size_t points, size_t segments) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  checkSize(option, modelFileBytes(points, segments, ext == ".xyz"),
            fmt::format("writing {} points and {} segments to '{}'", points, segments, path));
}

void checkGeometry(const std::string& input, size_t points, int k) {
  checkSize(input, pointGeometryBytes(points, k), fmt::format("the geometry (§6.1) of {} points (k = {})", points, k));
}

}  // namespace linesurf::cli
