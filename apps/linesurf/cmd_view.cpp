// linesurf view MODEL [-o model.html]: one self-contained HTML page that draws the model with
// WebGL2 (GPU point and line-segment splatting, thesis §4-§6.2 and §9.3). Raw scans get normals
// and radii from the geometry stage (§6.1) first, as for `linesurf render`.
// linesurf view MODEL.lod: the same viewer served from localhost, streaming the hierarchy's nodes
// by HTTP Range requests within a splat budget (lod_server.h).
#include <fmt/format.h>

#include <cctype>
#include <cstdio>
#include <filesystem>

#include "command.h"
#include "drawable_model.h"
#include "linesurf/core/error.h"
#include "linesurf/core/timer.h"
#include "linesurf/io/las_io.h"
#include "linesurf/io/model_io.h"
#include "linesurf/lod/lod.h"
#include "linesurf/pipeline/render_job.h"
#include "linesurf/render/renderer.h"
#include "linesurf/view/viewer_page.h"
#include "lod_server.h"
#include "options_bind.h"

namespace linesurf::cli {
namespace {

struct ViewArgs {
  std::string model, output;
  ViewerPageOptions page;  // its view and render fields bound from the option tables
  PrepareOptions prepare;
  size_t maxPrimitives = ViewerPageOptions{}.maxPrimitives;
  // .lod hierarchies: served, not written
  int port = 8080;
  std::string host = "127.0.0.1";
  bool allowRemote = false;
  double headerSeconds = kDefaultHeaderSeconds;
  uint64_t budget = 1'000'000;
  CLI::Option *portOption = nullptr, *hostOption = nullptr, *budgetOption = nullptr, *outputOption = nullptr,
              *allowRemoteOption = nullptr, *headerTimeoutOption = nullptr;
  const CLI::Option* upAxisFlag = nullptr;  ///< --up-axis: a file's recorded axis applies when not given
};

// A hierarchy: check its header and node table, then serve the page and the file until stopped.
void serveHierarchy(const ViewArgs& a, ViewerPageOptions o) {
  if (a.outputOption->count()) throwBadOption("output", "does not apply to a .lod hierarchy (it is served, not written)");
  // The server answers anyone who reaches it: another machine only when asked for in so many words.
  if (!isLoopbackHost(a.host) && !a.allowRemote)
    throwBadOption("host", a.host + " is not a loopback address (other machines could read the file); add --allow-remote to serve there");
  if (!(a.headerSeconds >= 0.05 && a.headerSeconds <= 3600))
    throwBadOption("header-timeout", fmt::format("expected seconds in [0.05, 3600], got {}", a.headerSeconds));
  const lod::LodFile file(a.model);  // throws BadInput naming the file when it is not a valid hierarchy
  std::error_code ec;
  const uint64_t bytes = std::filesystem::file_size(a.model, ec);
  o.renderArguments = fmt::format("--budget {}", a.budget);
  // A hierarchy built from a z-up model (LAS) records its axis: the page orbits about it.
  if (const std::string& up = file.header().upAxis;
      !up.empty() && a.upAxisFlag && a.upAxisFlag->count() == 0 && !o.view.eye && !o.view.target) {
    o.view.upAxis = parseUpAxis(up);
    say(fmt::format("{}: up axis {} (recorded in the hierarchy; --up-axis overrides)", a.model, up));
  }
  LodServeOptions s;
  s.host = a.host;
  s.port = a.port;
  s.headerSeconds = a.headerSeconds;
  s.file = a.model;
  s.page = lodViewerPage(file.header(), {.url = "/model.lod", .fileBytes = bytes, .budget = a.budget}, o);
  s.listening = [&](int port) {
    // One line for people and scripts (the port when --port 0), printed even with --quiet.
    std::printf("serving %s at http://%s:%d/ (Ctrl-C stops)\n", a.model.c_str(),
                a.host.find(':') != std::string::npos ? ("[" + a.host + "]").c_str() : a.host.c_str(), port);
    std::fflush(stdout);
  };
  s.report = [](const std::string& line) {  // printed even with --quiet, like the address
    std::printf("%s\n", line.c_str());
    std::fflush(stdout);
  };
  say(fmt::format("{}: {} nodes, {} points + {} segments, {:.1f} MB; initial budget {} splats", a.model,
                  file.nodes().size(), file.header().points, file.header().segments, double(bytes) / 1e6, a.budget));
  serveLod(s);
}

void run(const ViewArgs& a) {
  Timer total;
  ViewerPageOptions o = a.page;
  validate(o.view);
  validate(o.render);
  validate(a.prepare);
  // The page's title: printable UTF-8 whatever bytes the file name holds (oneLine escapes the rest).
  o.name = oneLine(std::filesystem::path(a.model).filename().string());
  o.maxPrimitives = a.maxPrimitives;
  // By content, or by name: a damaged file named .lod is refused as a hierarchy, naming it.
  std::string ext = std::filesystem::path(a.model).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (lod::isLodFile(a.model) || ext == ".lod") return serveHierarchy(a, o);
  for (const CLI::Option* opt : {a.portOption, a.hostOption, a.allowRemoteOption, a.headerTimeoutOption, a.budgetOption})
    if (opt->count()) throwBadOption(opt->get_name().substr(2), "needs a level-of-detail hierarchy (linesurf lod build), got " + a.model);
  const std::string out =
      a.output.empty() ? std::filesystem::path(a.model).filename().replace_extension(".html").string() : a.output;
  checkFiles({a.model}, {{"--output", out, {".html", ".htm"}}});

  HybridModel model = readDrawableModel(a.model);
  if (fileHoldsMesh(a.model)) o.renderArguments = "--primitive points";  // render draws a mesh's faces
  // Refuse before the geometry stage: a model over the budget costs nothing more.
  const size_t primitives = model.points.size() + model.segments.size();
  if (primitives > a.maxPrimitives)
    throw Error(Error::Kind::BadInput, a.model, "view",
                fmt::format("{} primitives exceed the viewer's budget of {} (--max-primitives)", primitives,
                            a.maxPrimitives));

  // The page holds every primitive as base64 floats (about 60 bytes a point, twice for a segment).
  checkSize("--output", 262144.0 + 60.0 * double(model.points.size()) + 120.0 * double(model.segments.size()),
            fmt::format("a page of {} points and {} segments", model.points.size(), model.segments.size()));
  checkGeometry(a.model, model.points.size(), a.prepare.k);
  completePointGeometry(model, a.prepare.k);
  // LAS is z-up, and a file made from one says so: the page orbits about its axis unless told otherwise.
  if (const std::string up = recordedUpAxis(model);
      !up.empty() && a.upAxisFlag && a.upAxisFlag->count() == 0 && !o.view.eye && !o.view.target) {
    o.view.upAxis = parseUpAxis(up);
    say(fmt::format("{}: up axis {} (recorded in the file; --up-axis overrides)", a.model, up));
  }
  // The page culls back faces as render does: its first view checked as render checks it, so that
  // normals facing away are said here and not found in an almost empty page.
  {
    RenderOptions ro = o.render;
    ro.facingCheck = true;
    const Renderer r(model, ro);
    ViewOptions v = o.view;
    v.width = v.height = Renderer::kFacingCheckSide;
    v.views = 0;
    const RenderResult first = r.render(viewCameras(r.sphere(), v).front());
    if (const std::string w = backFacingWarning(first.stats, a.model); !w.empty()) std::fprintf(stderr, "warning: %s\n", w.c_str());
  }

  ViewerPageStats st;
  try {
    st = writeViewerPage(out, model, o);
  } catch (const Error& e) {
    if (e.path() == o.name) throw Error(e.kind(), a.model, e.where(), e.reason());  // name the path typed
    throw;
  }
  if (st.skippedPoints || st.skippedSegments)
    say(fmt::format("left out {} points and {} segments (non-finite or zero radius)", st.skippedPoints,
                    st.skippedSegments));
  say(fmt::format("page: {} points + {} segments, {:.1f} MB, in {:.2f} s", st.points, st.segments,
                  double(st.bytes) / 1e6, total.seconds()));
  say("wrote " + out + " (a WebGL2 page; camera in the URL: #eye=X,Y,Z&target=X,Y,Z&up=X,Y,Z&fov=DEG)");
}

RegisterCommand reg(45, [](CLI::App& app) {
  auto a = std::make_shared<ViewArgs>();
  CLI::App* sub = app.add_subcommand(
      "view", "Write a self-contained HTML page that draws the model with WebGL2 splats (orbit, zoom, pan); "
              "serve a .lod hierarchy's viewer from localhost, streaming its nodes within a splat budget");
  sub->add_option("MODEL", a->model,
                  "Point cloud, hybrid or line model (.ply, .xyz; a mesh shows its vertices), or a .lod hierarchy "
                  "(linesurf lod build)")
      ->required();  // a missing file is reported after the options are checked, as render does
  a->outputOption = sub->add_option("-o,--output", a->output, "Output HTML page (default: MODEL's name with .html, here)")->type_name("FILE");
  // The page's defaults: the option tables' viewer fields (pipeline/option_tables.h).
  a->upAxisFlag = bindOptions(sub, a->page.view, {}, kUseViewer).option("upAxis");
  bindOptions(sub, a->page.render, {}, kUseViewer);
  bindOptions(sub, a->prepare, {"k"});
  sub->add_option("--max-primitives", a->maxPrimitives, "Refuse models with more points + segments than this")
      ->capture_default_str()
      ->check(CLI::Range(size_t(1), size_t(1) << 40));
  // A .lod hierarchy is served from localhost instead (its nodes streamed within a splat budget).
  a->portOption = sub->add_option("--port", a->port, "With a .lod hierarchy: the HTTP port to serve on (0: any free port)")
                      ->capture_default_str()
                      ->check(CLI::Range(0, 65535));
  a->hostOption = sub->add_option("--host", a->host,
                                  "With a .lod hierarchy: the address to serve on (one that is not loopback needs "
                                  "--allow-remote)")
                      ->capture_default_str();
  a->allowRemoteOption = sub->add_flag("--allow-remote", a->allowRemote,
                                       "With a .lod hierarchy: let --host be an address other machines can reach");
  a->headerTimeoutOption =
      sub->add_option("--header-timeout", a->headerSeconds,
                      "With a .lod hierarchy: seconds a request's header may take from its connection's accept "
                      "before the connection is closed")
          ->capture_default_str();
  a->budgetOption = sub->add_option("--budget", a->budget,
                                    "With a .lod hierarchy: the page's initial splat budget (its panel changes it)")
                        ->capture_default_str()
                        ->check(CLI::Range(uint64_t(1), uint64_t(1) << 40));
  sub->callback([a] { run(*a); });
});

}  // namespace
}  // namespace linesurf::cli
