// linesurf view MODEL [-o model.html]: one self-contained HTML page that draws the model with
// WebGL2 (GPU point and line-segment splatting, thesis §4-§6.2 and §9.3). Raw scans get normals
// and radii from the geometry stage (§6.1) first, as for `linesurf render`.
#include <fmt/format.h>

#include <filesystem>

#include "command.h"
#include "drawable_model.h"
#include "linesurf/core/error.h"
#include "linesurf/core/timer.h"
#include "linesurf/io/model_io.h"
#include "linesurf/pipeline/render_job.h"
#include "linesurf/view/viewer_page.h"
#include "options_bind.h"

namespace linesurf::cli {
namespace {

struct ViewArgs {
  std::string model, output;
  ViewerPageOptions page;  // its view and render fields bound from the option tables
  PrepareOptions prepare;
  size_t maxPrimitives = ViewerPageOptions{}.maxPrimitives;
};

void run(const ViewArgs& a) {
  Timer total;
  ViewerPageOptions o = a.page;
  validate(o.view);
  validate(o.render);
  validate(a.prepare);
  // The page's title: printable UTF-8 whatever bytes the file name holds (oneLine escapes the rest).
  o.name = oneLine(std::filesystem::path(a.model).filename().string());
  o.maxPrimitives = a.maxPrimitives;
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
      "view", "Write a self-contained HTML page that draws the model with WebGL2 splats (orbit, zoom, pan)");
  sub->add_option("MODEL", a->model, "Point cloud, hybrid or line model (.ply, .xyz); a mesh shows its vertices")
      ->required();  // a missing file is reported after the options are checked, as render does
  sub->add_option("-o,--output", a->output, "Output HTML page (default: MODEL's name with .html, here)");
  // The page's defaults: the option tables' viewer fields (pipeline/option_tables.h).
  bindOptions(sub, a->page.view, {}, kUseViewer);
  bindOptions(sub, a->page.render, {}, kUseViewer);
  bindOptions(sub, a->prepare, {"k"});
  sub->add_option("--max-primitives", a->maxPrimitives, "Refuse models with more points + segments than this")
      ->capture_default_str()
      ->check(CLI::Range(size_t(1), size_t(1) << 40));
  sub->callback([a] { run(*a); });
});

}  // namespace
}  // namespace linesurf::cli
