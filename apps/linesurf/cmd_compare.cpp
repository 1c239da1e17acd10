// linesurf compare A.png B.png [--diff out.png] [--json]: image metrics of thesis §7.
#include <fmt/format.h>

#include <nlohmann/json.hpp>

#include "command.h"
#include "linesurf/core/options.h"
#include "linesurf/core/error.h"
#include "linesurf/eval/image_metrics.h"
#include "linesurf/io/image_io.h"

namespace linesurf::cli {
namespace {

struct CompareArgs {
  std::string a, b, diff, holes;
  bool json = false;
  double saturate = 32;
};

void run(const CompareArgs& args) {
  requireRange("saturate", args.saturate, 1e-3, 1e6, "grey levels");  // CLI11's Range lets NaN through
  checkFiles({args.a, args.b}, {{"--diff", args.diff, {".png"}}, {"--holes", args.holes, {".png"}}});
  // Sizes from the headers before decoding: a small file may declare a huge image.
  const ImageInfo ia = readImageInfo(args.a), ib = readImageInfo(args.b);
  if (ia.width != ib.width || ia.height != ib.height)
    throw Error(Error::Kind::BadInput, args.b, "",
                fmt::format("size {}x{} differs from {} ({}x{})", ib.width, ib.height, args.a, ia.width, ia.height));
  checkSize(args.a, 16.0 * 3 * ia.width * ia.height, fmt::format("comparing {}x{} images", ia.width, ia.height));
  Image a = readImage(args.a, size_t(-1)), b = readImage(args.b, size_t(-1));
  ImageMetrics m = compareImages(a, b);
  if (!args.diff.empty()) writePng(args.diff, differenceHeatmap(a, b, args.saturate), false);
  const HoleMap holes = holeMap(a, b);  // cheap beside SSIM; reported always, written when asked
  if (!args.holes.empty()) writePng(args.holes, holes.map, false);
  if (args.json) {
    nlohmann::json j = {{"a", args.a}, {"b", args.b}, {"width", a.width}, {"height", a.height},
                        {"mse", m.mse}, {"psnr", std::isinf(m.psnr) ? nlohmann::json(nullptr) : nlohmann::json(m.psnr)},
                        {"nccm", m.nccm}, {"ssim", m.ssim}, {"mean_abs_diff", m.meanAbsDiff},
                        {"std_abs_diff", m.stdAbsDiff}, {"max_abs_diff", m.maxAbsDiff},
                        {"differing_pixels", m.differingPixels},
                        {"holes", {{"pixels", holes.holes}, {"share", holes.holeShare()}, {"reference_pixels", holes.referencePixels},
                                   {"extra_pixels", holes.extra}, {"by", holes.byAlpha ? "alpha" : "background"}}}};
    fmt::print("{}\n", j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace));  // names need not be UTF-8
    return;
  }
  say(fmt::format("{}x{} pixels", a.width, a.height));
  say(fmt::format("mse            {:.6f}  (RGB in [0,1])", m.mse));
  say(fmt::format("psnr           {}", std::isinf(m.psnr) ? std::string("inf (identical)") : fmt::format("{:.2f} dB", m.psnr)));
  say(fmt::format("nccm           {:.6f}", m.nccm));
  say(fmt::format("ssim           {:.6f}", m.ssim));
  say(fmt::format("abs diff       mean {:.3f}  std {:.3f}  max {:.0f}  (grey levels of 255)", m.meanAbsDiff, m.stdAbsDiff, m.maxAbsDiff));
  say(fmt::format("pixels > 1 lvl {:.3f}%", 100 * m.differingPixels));
  say(fmt::format("holes          {} pixels ({:.3f}% of the {} A covers) not covered in B; {} covered in B only ({})",
                  holes.holes, 100 * holes.holeShare(), holes.referencePixels, holes.extra,
                  holes.byAlpha ? "by alpha" : "against a white background"));
  if (!args.diff.empty()) say("difference heat-map: " + args.diff);
  if (!args.holes.empty()) say("hole map: " + args.holes);
}

RegisterCommand reg(60, [](CLI::App& app) {
  auto args = std::make_shared<CompareArgs>();
  CLI::App* sub = app.add_subcommand("compare", "Compare two images: mse, PSNR, nccm, SSIM, absolute differences (thesis §7)");
  sub->add_option("A", args->a, "First image (reference)")->type_name("FILE")->required();
  sub->add_option("B", args->b, "Second image")->type_name("FILE")->required();
  sub->add_option("--diff", args->diff, "Write a difference heat-map PNG")->type_name("FILE");
  sub->add_option("--saturate", args->saturate, "Grey-level difference shown as white in the heat-map")->check(CLI::Range(1e-3, 1e6));
  sub->add_option("--holes", args->holes, "Write the hole map: pixels A covers and B does not in red (A: a reference, "
                                          "e.g. render --primitive surface)")->type_name("FILE");
  sub->add_flag("--json", args->json, "Machine-readable output");
  sub->callback([args] { run(*args); });
});

}  // namespace
}  // namespace linesurf::cli
