// One source of truth for options (docs/decisions.md "Python module and options"): field -> flag /
// keyword naming, validate() on every option struct rejecting NaN and out-of-range values, and the
// CLI's exit code 1 with a one-line message naming the flag the user typed.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "linesurf/core/options.h"
#include "linesurf/extract/contour.h"
#include "linesurf/extract/eps_delta.h"
#include "linesurf/extract/shape_approx.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/pipeline/render_job.h"
#include "linesurf/render/render_options.h"
#include "test_util.h"

namespace linesurf {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

template <typename F>
std::string failingField(F&& f) {
  try {
    f();
  } catch (const OptionError& e) {
    return e.field();
  }
  return "";
}

TEST(OptionNames, OneRuleForFlagsAndKeywords) {
  EXPECT_EQ(flagName("zThreshold"), "--z-threshold");
  EXPECT_EQ(flagName("k"), "--k");
  EXPECT_EQ(flagName("prefilterVariance"), "--prefilter-variance");
  EXPECT_EQ(keywordName("zThreshold"), "z_threshold");
  EXPECT_EQ(keywordName("deltaN"), "delta_n");
  EXPECT_EQ(keywordName("fov"), "fov");
}

TEST(OptionValidation, DefaultsAreValid) {
  EXPECT_NO_THROW(validate(RenderOptions{}));
  EXPECT_NO_THROW(validate(ViewOptions{}));
  EXPECT_NO_THROW(validate(PrepareOptions{}));
  EXPECT_NO_THROW(validate(GeometryOptions{}));
  EXPECT_NO_THROW(validate(EpsDeltaOptions{}));
  EXPECT_NO_THROW(validate(ShapeApproxOptions{}));
  EXPECT_NO_THROW(validate(ContourOptions{}));
}

TEST(OptionValidation, NaNIsRejectedAndTheFieldNamed) {
  EXPECT_EQ(failingField([] { validate(RenderOptions{.prefilterVariance = kNaN}); }), "prefilterVariance");
  EXPECT_EQ(failingField([] { validate(RenderOptions{.zThreshold = kNaN}); }), "zThreshold");
  EXPECT_EQ(failingField([] { RenderOptions o; o.material.shininess = kNaN; validate(o); }), "shininess");
  EXPECT_EQ(failingField([] { validate(RenderOptions{.alphaOverride = kNaN}); }), "alphaOverride");
  EXPECT_EQ(failingField([] { validate(ViewOptions{.azimuth = kNaN}); }), "azimuth");
  EXPECT_EQ(failingField([] { validate(ViewOptions{.zoom = kNaN}); }), "zoom");
  EXPECT_EQ(failingField([] { validate(ViewOptions{.fov = kNaN}); }), "fov");
  EXPECT_EQ(failingField([] { ViewOptions v; v.eye = Vec3f(0, kNaN, 0); validate(v); }), "eye");
  EXPECT_EQ(failingField([] { validate(PrepareOptions{.radiusScale = kNaN}); }), "radiusScale");
  EXPECT_EQ(failingField([] { validate(GeometryOptions{.orientationPenalty = kNaN}); }), "orientationPenalty");
  EXPECT_EQ(failingField([] { validate(EpsDeltaOptions{.epsilon = kNaN}); }), "epsilon");
  EXPECT_EQ(failingField([] { validate(EpsDeltaOptions{.epsilonRelative = kNaN}); }), "epsilonRelative");
  EXPECT_EQ(failingField([] { validate(EpsDeltaOptions{.delta = kNaN}); }), "delta");
  EXPECT_EQ(failingField([] { ShapeApproxOptions o; o.clustering.deltaN = kNaN; validate(o); }), "deltaN");
  EXPECT_EQ(failingField([] { validate(ShapeApproxOptions{.radiusScale = kNaN}); }), "radiusScale");
  EXPECT_EQ(failingField([] { validate(ContourOptions{.spacing = kNaN}); }), "spacing");
  EXPECT_EQ(failingField([] { validate(ContourOptions{.familySwitchSine = kNaN}); }), "familySwitchSine");
}

TEST(OptionValidation, OutOfRangeIsRejectedNotClamped) {
  EXPECT_EQ(failingField([] { validate(RenderOptions{.layers = 0}); }), "layers");
  EXPECT_EQ(failingField([] { validate(RenderOptions{.cutoffRadius = 9}); }), "cutoffRadius");
  EXPECT_EQ(failingField([] { validate(RenderOptions{.alphaOverride = 1.5f}); }), "alphaOverride");
  EXPECT_EQ(failingField([] { validate(ViewOptions{.width = 0}); }), "size");
  EXPECT_EQ(failingField([] { validate(ViewOptions{.elevation = 91}); }), "elevation");
  EXPECT_EQ(failingField([] { validate(ViewOptions{.views = -1}); }), "views");
  EXPECT_EQ(failingField([] { validate(PrepareOptions{.k = 2}); }), "k");
  EXPECT_EQ(failingField([] { validate(GeometryOptions{.k = 300}); }), "k");
  EXPECT_EQ(failingField([] { validate(EpsDeltaOptions{.delta = 3}); }), "delta");
  EXPECT_EQ(failingField([] { validate(EpsDeltaOptions{.minReplaced = 1}); }), "minReplaced");
  EXPECT_EQ(failingField([] { ShapeApproxOptions o; o.clustering.deltaN = 2; validate(o); }), "deltaN");
  EXPECT_EQ(failingField([] { validate(ContourOptions{.familySwitchSine = 2}); }), "familySwitchSine");
  EXPECT_EQ(failingField([] { parseUpAxis("w"); }), "upAxis");
  EXPECT_EQ(failingField([] { parseBackground("1,2,3"); }), "background");
}

TEST(OptionValidation, ZThresholdDefaultDependsOnTheMode) {
  EXPECT_FALSE(RenderOptions{}.zThreshold.has_value());  // the mode's default
  EXPECT_EQ(zThresholdOf(RenderOptions{}), defaultZThreshold(ZThresholdMode::PerPrimitive));
  EXPECT_EQ(defaultZThreshold(ZThresholdMode::PerPrimitive), 0.5f);
  EXPECT_EQ(defaultZThreshold(ZThresholdMode::Fixed), 0.01f);
}

// The CLI: exit code 1 and exactly one line naming the flag, for NaN and out-of-range values.
TEST(CliOptions, BadValuesExitOneNamingTheFlag) {
  const std::string model = (test::bundledData() / "igea_points.ply").string();
  const std::string out = (test::scratchDir("cli_options") / "x.ply").string();
  struct Case {
    std::string args, flag;
  };
  const Case cases[] = {
      {"render " + model + " -o " + out + ".png --prefilter-variance nan", "--prefilter-variance"},
      {"render " + model + " -o " + out + ".png --z-threshold nan", "--z-threshold"},
      {"render " + model + " -o " + out + ".png --zoom nan", "--zoom"},
      {"render " + model + " -o " + out + ".png --fov 200", "--fov"},
      {"render " + model + " -o " + out + ".png --elevation nan", "--elevation"},
      {"render " + model + " -o " + out + ".png --alpha 2", "--alpha-override"},
      {"render " + model + " -o " + out + ".png --shininess nan", "--shininess"},
      {"render " + model + " -o " + out + ".png --radius-scale nan", "--radius-scale"},
      {"render " + model + " -o " + out + ".png --size 0x10", "--size"},
      {"render " + model + " -o " + out + ".png --up-axis w", "--up-axis"},
      {"render " + model + " -o " + out + ".png --eye 0 nan 1", "--eye"},
      {"extract eps-delta " + model + " -o " + out + " --delta nan", "--delta"},
      {"extract eps-delta " + model + " -o " + out + " --epsilon-relative nan", "--epsilon-relative"},
      {"extract eps-delta " + model + " -o " + out + " -k 2", "--k"},
      {"extract eps-delta " + model + " -o " + out + " --orientation-penalty nan", "--orientation-penalty"},
      {"extract shape-approx " + model + " -o " + out + " --delta-n nan", "--delta-n"},
      {"extract shape-approx " + model + " -o " + out + " --radius-scale -1", "--radius-scale"},
      {"extract contour " + model + " -o " + out + " --family-switch-sine nan", "--family-switch-sine"},
      {"normals " + model + " -o " + out + " --k 1000", "--k"},
  };
  for (const Case& c : cases) {
    auto r = test::runCli(c.args);
    EXPECT_EQ(r.exitCode, 1) << c.args << "\n" << r.out;
    EXPECT_EQ(r.out.rfind(c.flag + ": ", 0), 0u) << c.args << "\n" << r.out;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << c.args << "\n" << r.out;
  }
  EXPECT_FALSE(std::filesystem::exists(out));
}

}  // namespace
}  // namespace linesurf
