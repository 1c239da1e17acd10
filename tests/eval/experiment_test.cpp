// The §7 experiment harness: a smoke run on the bundled models (few views, small images), failure
// handling, determinism, the thesis's figures and the CLI.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "shapes.h"
#include "linesurf/eval/experiment.h"
#include "linesurf/io/model_io.h"
#include "test_util.h"

using namespace linesurf;
namespace fs = std::filesystem;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// A folder with one small sphere cloud (fast to process) and optionally a broken PLY.
fs::path sphereFolder(const std::string& name, bool withBroken) {
  fs::path dir = test::scratchDir(name);
  HybridModel s = shapes::sphere(1.0f, 600);
  s.attributes.normals = false;  // a raw scan: the harness derives normals and radii (§6.1)
  for (Point& p : s.points) p.normal = Vec3f::Zero();
  writeModel(dir / "ball_points.ply", s);
  if (withBroken) {
    std::ofstream(dir / "broken.ply") << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\n";
  }
  std::ofstream(dir / "README.md") << "not a model\n";
  return dir;
}

ExperimentOptions fastOptions(const fs::path& dir) {
  ExperimentOptions o;
  o.dataDir = dir;
  o.views = 1;
  o.meshViews = 1;
  o.size = 64;
  o.imageViews = 0;
  return o;
}

}  // namespace

// The smoke run of the issue: every bundled model, 2 views at 128x128. Bounds: no model fails;
// every method gives segments and fewer primitives than the point model; nccm within 1% of 1 and
// the mean absolute difference below 3 grey levels (of 255) on average over the views. The thesis
// reports nccm >= 0.997 and means <= 0.31 at 512x512; the full run in docs/results.md holds our
// figures against those, this bound only catches a broken pipeline (blank or misplaced images).
TEST(Experiment, SmokeRunOnBundledModels) {
  ExperimentOptions o;
  o.dataDir = test::bundledData();
  // The three small bundled models of the issue (data/ also holds the 134k-point Igea, for the demo).
  o.only = {"santa_points", "rockerarm_points", "al_mesh"};
  o.outDir = test::scratchDir("experiment_smoke");
  o.views = 2;
  o.meshViews = 2;
  o.size = 128;
  o.imageViews = 1;
  std::vector<double> fractions;
  const ExperimentResults r = runExperiment(o, [&](std::string_view, double f) { fractions.push_back(f); });

  ASSERT_EQ(r.models.size(), 3u);  // README.md is not a model, Igea is left out
  EXPECT_EQ(r.failedCount(), 0u);
  EXPECT_FALSE(fractions.empty());
  for (size_t i = 1; i < fractions.size(); ++i) EXPECT_GE(fractions[i], fractions[i - 1] - 1e-12);
  EXPECT_LE(fractions.back(), 1.0 + 1e-12);
  for (const ModelResult& m : r.models) {
    SCOPED_TRACE(m.name + ": " + m.error);
    ASSERT_FALSE(m.failed);
    EXPECT_FALSE(m.thesisName.empty());
    EXPECT_EQ(m.isMesh, m.name == "al_mesh");
    ASSERT_EQ(m.methods.size(), m.isMesh ? 1u : 3u);
    EXPECT_EQ(m.referenceImages.size(), 1u);
    for (const MethodResult& mr : m.methods) {
      SCOPED_TRACE(experimentMethodName(mr.method));
      EXPECT_GT(mr.referencePoints, 0u);
      EXPECT_GT(mr.segments, 0u);
      EXPECT_LT(mr.points + mr.segments, mr.referencePoints);
      EXPECT_GT(mr.dataReduction, 0.0);
      EXPECT_LT(mr.dataReduction, 1.0);
      ASSERT_EQ(mr.views.size(), 2u);
      EXPECT_NEAR(mr.nccm, 1.0, 0.01);
      // 3 grey levels: Al's coarse facets at 128x128 (2.5; 3.2 before the contour points and
      // strip planes followed the smooth line model's interpolated normals)
      EXPECT_LE(mr.meanAbsDiff.mean, 3.0);
      EXPECT_GE(mr.ssim, 0.9);
      if (m.isMesh) {  // the contour point model's points carry masses by default
        ASSERT_FALSE(mr.notes.empty());
        EXPECT_NE(mr.notes[0].find("(masses)"), std::string::npos) << mr.notes[0];
      }
      EXPECT_TRUE(std::isfinite(mr.speedup));
      EXPECT_GT(mr.referenceRenderMedian, 0.0);
      if (mr.method == ExperimentMethod::ShapeGreedy || mr.method == ExperimentMethod::ShapeHierarchical) {
        EXPECT_GT(mr.clusters, 0u);
        EXPECT_LE(mr.clusters, mr.referencePoints);
        ASSERT_FALSE(mr.clustersImage.empty());
        EXPECT_TRUE(fs::exists(o.outDir / mr.clustersImage));
      }
      ASSERT_FALSE(mr.structureImage.empty());
      EXPECT_TRUE(fs::exists(o.outDir / mr.structureImage));
      ASSERT_FALSE(mr.viewerPage.empty());  // the 3D viewer page linked from the report
      EXPECT_TRUE(fs::exists(o.outDir / mr.viewerPage));
      ASSERT_EQ(mr.images.size(), 1u);
      EXPECT_TRUE(fs::exists(o.outDir / mr.images[0]));
      EXPECT_TRUE(fs::exists(o.outDir / mr.diffImages[0]));
      // meshes: both models against the mesh rendered itself (ground truth); the line and the
      // point model of Al look like the mesh (SSIM 0.71 / 0.70 at 128x128 over 2 views, 0.86 /
      // 0.84 at 512x512 over 20) but far from a pixel match; a broken camera or framing < 0.5
      // The surface error column: every extraction's surface within a few epsilon_ref of the
      // input's (a contour model's of its mesh) at the RMS, and no projection failing wholesale.
      ASSERT_TRUE(mr.surface.has_value());
      EXPECT_EQ(mr.surface->meshReference, m.isMesh);
      EXPECT_GT(mr.surface->both.samples, 1000u);
      EXPECT_LT(double(mr.surface->failures()), 0.01 * double(mr.surface->both.samples));
      EXPECT_GT(mr.surface->both.rms, 0.0);
      EXPECT_LT(mr.surface->both.rms, 3 * mr.surface->epsilonRef);
      EXPECT_LE(mr.surface->both.p99, mr.surface->both.max);
      EXPECT_EQ(mr.hasTruth, m.isMesh);
      if (m.isMesh) {
        ASSERT_EQ(m.truthImages.size(), 1u);
        EXPECT_TRUE(fs::exists(o.outDir / m.truthImages[0]));
        EXPECT_TRUE(mr.views[0].hasTruth);
        EXPECT_GT(mr.views[0].coveredPixels, 128u * 128u / 10);
        EXPECT_GT(mr.candidateTruth.ssim, 0.65);
        EXPECT_GT(mr.referenceTruth.ssim, 0.65);
        EXPECT_LT(mr.candidateTruth.badFraction, 0.3);
        EXPECT_LT(mr.referenceTruth.badFraction, 0.3);
        // the part away from the mesh's silhouettes is a part, and the band is neither empty nor all
        EXPECT_LE(mr.candidateTruth.badOffSilhouettesFraction, mr.candidateTruth.badFraction);
        EXPECT_LE(mr.referenceTruth.badOffSilhouettesFraction, mr.referenceTruth.badFraction);
        EXPECT_GT(mr.candidateTruth.silhouetteBandFraction, 0.01);
        EXPECT_LT(mr.candidateTruth.silhouetteBandFraction, 0.9);
      }
    }
  }

  writeExperimentJson(r, o.outDir / "results.json");
  writeExperimentMarkdown(r, o.outDir / "results.md");
  writeExperimentHtml(r, o.outDir / "index.html");
  const nlohmann::json j = nlohmann::json::parse(slurp(o.outDir / "results.json"));
  EXPECT_EQ(j["failed"], 0);
  ASSERT_EQ(j["models"].size(), 3u);
  EXPECT_EQ(j["models"][0]["name"], "al_mesh");
  EXPECT_EQ(j["models"][0]["methods"][0]["views"].size(), 2u);
  const std::string md = slurp(o.outDir / "results.md");
  for (const char* s : {"Table 1", "Table 2", "Table 3", "Table 4", "Table 5", "Rocker arm", "Santa", "| Al |"})
    EXPECT_NE(md.find(s), std::string::npos) << s;
  const std::string html = slurp(o.outDir / "index.html");
  EXPECT_NE(html.find("santa_points/shape-greedy/clusters.png"), std::string::npos);
  EXPECT_NE(html.find("rockerarm_points/view_000_points.png"), std::string::npos);
  EXPECT_NE(html.find("al_mesh/view_000_mesh.png"), std::string::npos);
  EXPECT_NE(md.find("Against the mesh"), std::string::npos);
  EXPECT_TRUE(j["models"][0]["methods"][0].contains("candidate_vs_mesh"));
  EXPECT_EQ(j["models"][0]["methods"][0]["surface_error"]["reference"], "mesh");
  EXPECT_TRUE(j["models"][1]["methods"][0]["surface_error"]["both"].contains("p99_eps_ref"));
  EXPECT_NE(md.find("Surface error (× ε_ref)"), std::string::npos);
  EXPECT_TRUE(j["models"][0]["methods"][0]["views"][0].contains("reference_vs_mesh"));
  EXPECT_TRUE(j["models"][0]["methods"][0]["candidate_vs_mesh"].contains("fraction_over_64_off_silhouettes"));
  EXPECT_NE(html.find("href=\"rockerarm_points/points.html\""), std::string::npos);
  EXPECT_NE(html.find("href=\"santa_points/shape-greedy/viewer.html\""), std::string::npos);
}

TEST(Experiment, BadFileIsRecordedAndTheRunContinues) {
  ExperimentOptions o = fastOptions(sphereFolder("experiment_bad", true));
  o.methods = {ExperimentMethod::EpsDelta};
  const ExperimentResults r = runExperiment(o);
  ASSERT_EQ(r.models.size(), 2u);
  EXPECT_EQ(r.failedCount(), 1u);
  EXPECT_EQ(r.models[0].name, "ball_points");
  EXPECT_FALSE(r.models[0].failed);
  EXPECT_EQ(r.models[1].name, "broken");
  EXPECT_TRUE(r.models[1].failed);
  EXPECT_NE(r.models[1].error.find("broken.ply"), std::string::npos) << r.models[1].error;
  EXPECT_TRUE(r.models[1].methods.empty());
}

TEST(Experiment, SameInputsGiveSameResultsExceptTimings) {
  const ExperimentOptions o = fastOptions(sphereFolder("experiment_determinism", false));
  const ExperimentResults a = runExperiment(o);
  ExperimentResults b;
  {
    ThreadLimit one(1);  // and for any thread count
    b = runExperiment(o);
  }
  ASSERT_EQ(a.models.size(), 1u);
  ASSERT_EQ(a.models[0].methods.size(), b.models[0].methods.size());
  for (size_t i = 0; i < a.models[0].methods.size(); ++i) {
    const MethodResult &x = a.models[0].methods[i], &y = b.models[0].methods[i];
    EXPECT_EQ(x.points, y.points);
    EXPECT_EQ(x.segments, y.segments);
    EXPECT_EQ(x.clusters, y.clusters);
    EXPECT_EQ(x.mse, y.mse);
    EXPECT_EQ(x.nccm, y.nccm);
    EXPECT_EQ(x.meanAbsDiff.mean, y.meanAbsDiff.mean);
    ASSERT_TRUE(x.surface && y.surface);
    EXPECT_EQ(x.surface->both.rms, y.surface->both.rms);
    EXPECT_EQ(x.surface->both.max, y.surface->both.max);
  }
}

TEST(Experiment, RejectsAbsurdOptionsAndEmptyFolders) {
  ExperimentOptions o = fastOptions(sphereFolder("experiment_options", false));
  o.views = 0;
  EXPECT_THROW(runExperiment(o), Error);
  o.views = 1;
  o.size = 4;
  try {
    runExperiment(o);
    FAIL() << "size 4 accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), Error::Kind::BadParameter);
  }
  o = fastOptions(test::scratchDir("experiment_empty"));
  try {
    runExperiment(o);
    FAIL() << "empty folder accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), Error::Kind::BadInput);
  }
  EXPECT_THROW(parseExperimentMethod("fastest"), Error);
  EXPECT_EQ(parseExperimentMethod("greedy"), ExperimentMethod::ShapeGreedy);
  // Curvature lines (§9.2) run only when asked for, after the thesis's point methods.
  EXPECT_EQ(parseExperimentMethod("curvature-lines"), ExperimentMethod::CurvatureLines);
  ExperimentOptions d;
  const std::vector<ExperimentMethod> def = d.effectiveMethods();
  EXPECT_EQ(std::count(def.begin(), def.end(), ExperimentMethod::CurvatureLines), 0);
  d.methods = {ExperimentMethod::Contour, ExperimentMethod::CurvatureLines, ExperimentMethod::EpsDelta};
  EXPECT_EQ(d.effectiveMethods(), (std::vector<ExperimentMethod>{ExperimentMethod::EpsDelta, ExperimentMethod::CurvatureLines,
                                                                 ExperimentMethod::Contour}));
  EXPECT_EQ(thesisTableOf(ExperimentMethod::CurvatureLines), 6);
}

TEST(Experiment, ThesisModelsAndFigures) {
  EXPECT_EQ(thesisModelFor("al_mesh"), "Al");
  EXPECT_EQ(thesisModelFor("alpha_points"), "");
  EXPECT_EQ(thesisModelFor("igea_points"), "Igea artifact");
  EXPECT_EQ(thesisModelFor("rockerarm_points"), "Rocker arm");
  auto t1 = thesisFigures("Santa", 1);
  ASSERT_TRUE(t1);
  EXPECT_EQ(t1->points, 62360);
  EXPECT_NEAR(t1->speedup, 0.1257, 1e-12);
  auto t2 = thesisFigures("Golf club", 2);
  ASSERT_TRUE(t2);
  // §7.2.2: the Golf club of Table 2 has the maximum data reduction, 77.39%.
  EXPECT_NEAR(1 - (6 * t2->points + 9 * t2->segments) / (6 * t2->inputPoints), 0.7739, 5e-5);
  EXPECT_EQ(t2->clusters, 5576);
  auto t5 = thesisFigures("Buddha", 5);
  ASSERT_TRUE(t5);
  EXPECT_DOUBLE_EQ(t5->meanAbsDiff, 0.31);
  EXPECT_FALSE(thesisFigures("Bunny", 1));
}

TEST(Experiment, CliExitsNonZeroWhenAModelFails) {
  const fs::path bad = sphereFolder("experiment_cli_bad", true), out = test::scratchDir("experiment_cli_out");
  auto r = test::runCli("-q experiment " + bad.string() + " -o " + out.string() +
                        " --views 1 --size 64 --methods eps-delta --image-views 1");
  EXPECT_EQ(r.exitCode, 2) << r.out;
  EXPECT_NE(r.out.find("1 of 2 models failed"), std::string::npos) << r.out;
  EXPECT_TRUE(fs::exists(out / "results.json"));
  EXPECT_TRUE(fs::exists(out / "index.html"));
  const fs::path good = sphereFolder("experiment_cli_good", false);
  r = test::runCli("experiment " + good.string() + " -o " + out.string() + " --views 1 --size 64 --methods greedy");
  EXPECT_EQ(r.exitCode, 0) << r.out;
  EXPECT_NE(r.out.find("ball_points"), std::string::npos) << r.out;
  r = test::runCli("experiment " + good.string() + " -o " + out.string() + " --methods nonsense");
  EXPECT_EQ(r.exitCode, 1) << r.out;
  // the render options' validation names the experiment's flag
  r = test::runCli("experiment " + good.string() + " -o " + out.string() + " --views 1 --size 64 --methods greedy --prefilter-variance -1");
  EXPECT_EQ(r.exitCode, 1) << r.out;
  EXPECT_NE(r.out.find("--prefilter-variance"), std::string::npos) << r.out;
}

// The shared models are found and mapped to the thesis's names; one small cloud runs end to end.
TEST(SharedExperiment, ScrewdriverMapsToTheThesisAndRuns) {
  LINESURF_REQUIRE_SHARED_DATA();
  ExperimentOptions o = fastOptions(test::sharedData());
  o.only = {"screwdriver"};
  o.methods = {ExperimentMethod::EpsDelta, ExperimentMethod::ShapeGreedy};
  const ExperimentResults r = runExperiment(o);
  ASSERT_EQ(r.models.size(), 1u);
  const ModelResult& m = r.models[0];
  ASSERT_FALSE(m.failed) << m.error;
  EXPECT_EQ(m.thesisName, "Screwdriver");
  EXPECT_EQ(m.inputPoints, 3395u);
  ASSERT_EQ(m.methods.size(), 2u);
  for (const MethodResult& mr : m.methods) {
    EXPECT_LE(mr.points + mr.segments, mr.referencePoints);
    EXPECT_NEAR(mr.nccm, 1.0, 0.01);
  }
  EXPECT_TRUE(thesisFigures(m.thesisName, 1));
}
