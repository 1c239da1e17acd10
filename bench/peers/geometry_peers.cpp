// Side-by-side run of the §6.1 geometry stages: linesurf, Open3D 0.16 and CGAL 5.5 on the same
// clouds, in one process. Prints per-stage times (median of --reps), the ratios to the fastest
// peer, the mean angle between the normals, and orientation failures on analytic shapes.
//   geometry_peers [--k 12] [--reps 3] [--no-open3d-orient] FILE.ply...
#include <open3d/geometry/KDTreeFlann.h>
#include <open3d/geometry/PointCloud.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Orthogonal_k_neighbor_search.h>
#include <CGAL/Search_traits_3.h>
#include <CGAL/compute_average_spacing.h>
#include <CGAL/mst_orient_normals.h>
#include <CGAL/pca_estimate_normals.h>
#include <CGAL/property_map.h>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "linesurf/core/parallel.h"
#include "shapes.h"
#include "linesurf/core/timer.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"

using namespace linesurf;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using CPoint = K::Point_3;
using CVector = K::Vector_3;
using PN = std::pair<CPoint, CVector>;
using PointMap = CGAL::First_of_pair_property_map<PN>;
using NormalMap = CGAL::Second_of_pair_property_map<PN>;

namespace {

constexpr double kDeg = 180.0 / 3.14159265358979323846;

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

/// Runs f reps times, returns the median wall time.
double timed(int reps, const std::function<void()>& f) {
  std::vector<double> t;
  for (int r = 0; r < reps; ++r) {
    Timer timer;
    f();
    t.push_back(timer.seconds());
  }
  return median(t);
}

struct Row {
  std::string stage;
  double ours = NAN, open3d = NAN, cgal = NAN;
};

void printTable(const std::string& title, const std::vector<Row>& rows) {
  fmt::print("\n{}\n", title);
  fmt::print("| stage | linesurf | Open3D | CGAL | linesurf / fastest peer |\n|---|---|---|---|---|\n");
  auto cell = [](double v) { return std::isnan(v) ? std::string("–") : fmt::format("{:.3f}", v); };
  for (const Row& r : rows) {
    double peer = NAN;
    if (!std::isnan(r.open3d)) peer = r.open3d;
    if (!std::isnan(r.cgal)) peer = std::isnan(peer) ? r.cgal : std::min(peer, r.cgal);
    fmt::print("| {} | {} | {} | {} | {} |\n", r.stage, cell(r.ours), cell(r.open3d), cell(r.cgal),
               std::isnan(peer) || std::isnan(r.ours) ? std::string("–") : fmt::format("{:.2f}", r.ours / peer));
  }
}

/// Mean unsigned angle (degrees) and fraction of equal orientation between two normal sets.
std::pair<double, double> agreement(const std::vector<Vec3f>& a, const std::vector<Vec3f>& b) {
  double ang = 0, same = 0;
  size_t n = std::min(a.size(), b.size()), c = 0;
  for (size_t i = 0; i < n; ++i) {
    const float la = a[i].norm(), lb = b[i].norm();
    if (!(la > 0) || !(lb > 0) || !std::isfinite(la) || !std::isfinite(lb)) continue;
    const double d = double(a[i].dot(b[i]) / (la * lb));
    ang += std::acos(std::min(1.0, std::abs(d))) * kDeg;
    same += d > 0;
    ++c;
  }
  return {c ? ang / double(c) : NAN, c ? same / double(c) : NAN};
}

std::vector<Vec3f> fromO3d(const open3d::geometry::PointCloud& pc) {
  std::vector<Vec3f> v;
  for (const auto& nn : pc.normals_) v.push_back(nn.cast<float>());
  return v;
}
std::vector<Vec3f> fromCgal(const std::vector<PN>& pts) {
  std::vector<Vec3f> v;
  for (const auto& p : pts) v.emplace_back(float(p.second.x()), float(p.second.y()), float(p.second.z()));
  return v;
}

struct Options {
  int k = 12, reps = 3;
  bool open3dOrient = true;
};

void benchCloud(const std::string& name, const HybridModel& model, const Options& opt) {
  const size_t n = model.points.size();
  const int k = opt.k;
  // --- linesurf: every stage, then the whole pipeline.
  GeometryOptions go;
  go.k = k;
  go.recomputeNormals = true;
  std::vector<GeometryStageTimes> times;
  std::vector<double> whole;
  PointGeometry ours;
  for (int r = 0; r < opt.reps; ++r) {
    Timer t;
    ours = computePointGeometry(model, go);
    whole.push_back(t.seconds());
    times.push_back(ours.times);
  }
  auto med = [&](double GeometryStageTimes::*f) {
    std::vector<double> v;
    for (auto& t : times) v.push_back(t.*f);
    return median(v);
  };
  std::vector<double> knnNormals;
  for (auto& t : times) knnNormals.push_back(t.neighbours + t.normals);
  GeometryOptions cg = go;
  cg.cgalDelaunay = true;
  cg.curvature = false;
  double cgalDelaunay = timed(1, [&] { (void)computePointGeometry(model, cg); });
  (void)cgalDelaunay;

  // --- Open3D.
  open3d::geometry::PointCloud pc;
  for (const auto& p : model.points) pc.points_.push_back(p.position.cast<double>());
  double o3dKnn = timed(opt.reps, [&] {
    open3d::geometry::KDTreeFlann tree(pc);
    tbb::parallel_for(size_t(0), n, [&](size_t i) {
      std::vector<int> idx;
      std::vector<double> d2;
      tree.SearchKNN(pc.points_[i], k + 1, idx, d2);
    });
  });
  double o3dNormals = timed(opt.reps, [&] {
    pc.normals_.clear();
    pc.EstimateNormals(open3d::geometry::KDTreeSearchParamKNN(k));
  });
  auto o3dPca = fromO3d(pc);
  double o3dOrient = NAN;
  std::vector<Vec3f> o3dOriented;
  if (opt.open3dOrient) {
    o3dOrient = timed(1, [&] { pc.OrientNormalsConsistentTangentPlane(size_t(k)); });
    o3dOriented = fromO3d(pc);
  }

  // --- CGAL.
  std::vector<PN> pts;
  for (const auto& p : model.points) pts.emplace_back(CPoint(p.position.x(), p.position.y(), p.position.z()), CVector(0, 0, 0));
  using Traits = CGAL::Search_traits_3<K>;
  using Search = CGAL::Orthogonal_k_neighbor_search<Traits>;
  double cgalKnn = timed(opt.reps, [&] {
    Search::Tree tree;
    for (const auto& p : pts) tree.insert(p.first);
    tree.build();
    tbb::parallel_for(size_t(0), n, [&](size_t i) {
      Search s(tree, pts[i].first, unsigned(k + 1));
      volatile double sink = 0;
      for (auto it = s.begin(); it != s.end(); ++it) sink = sink + it->second;
    });
  });
  double cgalNormals = timed(opt.reps, [&] {
    CGAL::pca_estimate_normals<CGAL::Parallel_tag>(pts, k, CGAL::parameters::point_map(PointMap()).normal_map(NormalMap()));
  });
  auto cgalPca = fromCgal(pts);
  size_t cgalUnoriented = 0;
  double cgalOrient = timed(1, [&] {
    auto it = CGAL::mst_orient_normals(pts, k, CGAL::parameters::point_map(PointMap()).normal_map(NormalMap()));
    cgalUnoriented = size_t(std::distance(it, pts.end()));
  });
  std::vector<Vec3f> cgalOriented;
  {
    // mst_orient_normals reorders the points: map back by position.
    std::map<std::tuple<float, float, float>, Vec3f> byPos;
    for (const auto& p : pts)
      byPos[{float(p.first.x()), float(p.first.y()), float(p.first.z())}] =
          Vec3f(float(p.second.x()), float(p.second.y()), float(p.second.z()));
    for (const auto& p : model.points) cgalOriented.push_back(byPos[{p.position.x(), p.position.y(), p.position.z()}]);
  }
  double cgalSpacing = timed(opt.reps, [&] {
    volatile double s = CGAL::compute_average_spacing<CGAL::Parallel_tag>(pts, k, CGAL::parameters::point_map(PointMap()));
    (void)s;
  });

  std::vector<Row> rows = {
      {"kNN graph", med(&GeometryStageTimes::neighbours), o3dKnn, cgalKnn},
      {"PCA normals (incl. kNN)", median(knnNormals), o3dNormals, cgalNormals},
      {"MST orientation", med(&GeometryStageTimes::orientation), o3dOrient, cgalOrient},
      {"local Delaunay (stage 3)", med(&GeometryStageTimes::delaunay), NAN, NAN},
      {"curvature (Taubin, stage 4)", med(&GeometryStageTimes::curvature), NAN, NAN},
      {"average spacing (given kNN / standalone)", med(&GeometryStageTimes::spacing), NAN, cgalSpacing},
      {"whole pipeline (5 stages)", median(whole), NAN, NAN},
  };
  printTable(fmt::format("{}: {} points, k = {}, {} threads, seconds (median of {})", name, n, k,
                         currentThreadCount(), opt.reps), rows);
  fmt::print("local Delaunay with CGAL::Delaunay_triangulation_2 instead (stages 1-3 incl.): {:.3f} s\n", cgalDelaunay);
  auto [aO, sO] = agreement(ours.normals, o3dPca);
  auto [aC, sC] = agreement(ours.normals, cgalPca);
  fmt::print("mean angle between PCA normals: Open3D {:.3f} deg, CGAL {:.3f} deg\n", aO, aC);
  if (!o3dOriented.empty()) {
    auto [a, s] = agreement(ours.normals, o3dOriented);
    fmt::print("after orientation, same sign as linesurf: Open3D {:.2f}%", 100 * s);
    (void)a;
  }
  auto [a2, s2] = agreement(ours.normals, cgalOriented);
  (void)a2;
  fmt::print(", CGAL {:.2f}% ({} left unoriented)\n", 100 * s2, cgalUnoriented);
  fmt::print("linesurf: {} component(s), {} flips, average spacing {:.6g} (CGAL's definition is the same)\n",
             ours.orientationComponents, ours.orientationFlips, ours.averageSpacing);
}

/// Two unit spheres far apart (a disconnected neighbour graph).
HybridModel twoSpheres() {
  auto a = shapes::sphere(1, 10000), b = shapes::sphere(1, 10000, {.irregular = true, .seed = 8});
  for (auto& p : b.points) {
    p.position += Vec3f(5, 0, -1);
    a.points.push_back(p);
  }
  return a;
}

/// Orientation on analytic shapes: normals pointing inward (exact normals known).
void orientationShapes(const Options& opt) {
  struct Shape { std::string name; HybridModel m; };
  shapes::SampleOptions reg, irr{.noise = 0.15f, .irregular = true, .seed = 3};
  std::vector<Shape> list = {{"sphere 20k regular", shapes::sphere(1, 20000, reg)},
                             {"sphere 20k irregular+noise", shapes::sphere(1, 20000, irr)},
                             {"torus 30k regular", shapes::torus(2, 0.6f, 300, 100, reg)},
                             {"torus 30k irregular+noise", shapes::torus(2, 0.6f, 300, 100, irr)},
                             {"cylinder 20k regular (open)", shapes::cylinder(1, 4, 200, 100, reg)},
                             {"cylinder 20k irregular+noise", shapes::cylinder(1, 4, 200, 100, irr)},
                             {"two spheres 2 x 10k (disconnected)", twoSpheres()}};
  fmt::print("\nOrientation on analytic shapes (k = {}): normals pointing inward, and time (s)\n", opt.k);
  fmt::print("| shape | linesurf | Open3D | CGAL |\n|---|---|---|---|\n");
  for (auto& [name, m] : list) {
    auto inward = [&](const std::vector<Vec3f>& nn) {
      size_t c = 0;
      for (size_t i = 0; i < m.points.size(); ++i)
        if (!(nn[i].dot(m.points[i].normal) > 0)) ++c;
      return c;
    };
    GeometryOptions go;
    go.k = opt.k;
    go.recomputeNormals = true;
    go.delaunayNeighbours = go.curvature = false;
    Timer t;
    auto g = computePointGeometry(m, go);
    const double tOurs = t.seconds();
    std::string o3d = "–";
    if (opt.open3dOrient) {
      open3d::geometry::PointCloud pc;
      for (const auto& p : m.points) pc.points_.push_back(p.position.cast<double>());
      t.reset();
      pc.EstimateNormals(open3d::geometry::KDTreeSearchParamKNN(opt.k));
      pc.OrientNormalsConsistentTangentPlane(size_t(opt.k));
      const double tO = t.seconds();
      auto nn = fromO3d(pc);
      size_t c = inward(nn);
      // Open3D has no outside: count the better of the two global signs.
      o3d = fmt::format("{} ({:.2f} s)", std::min(c, m.points.size() - c), tO);
    }
    std::vector<PN> pts;
    for (const auto& p : m.points) pts.emplace_back(CPoint(p.position.x(), p.position.y(), p.position.z()), CVector(0, 0, 0));
    t.reset();
    CGAL::pca_estimate_normals<CGAL::Parallel_tag>(pts, opt.k, CGAL::parameters::point_map(PointMap()).normal_map(NormalMap()));
    auto it = CGAL::mst_orient_normals(pts, opt.k, CGAL::parameters::point_map(PointMap()).normal_map(NormalMap()));
    const double tC = t.seconds();
    size_t cgalIn = size_t(std::distance(it, pts.end()));  // unoriented count as failures
    for (auto p = pts.begin(); p != it; ++p) {
      const Vec3f pos(float(p->first.x()), float(p->first.y()), float(p->first.z()));
      // Exact outward normal of the analytic shape, recomputed from the position.
      Vec3f truth;
      if (name.rfind("sphere", 0) == 0) truth = pos;
      else if (name.rfind("two", 0) == 0) truth = pos.x() > 2.5f ? Vec3f(pos - Vec3f(5, 0, -1)) : pos;
      else if (name.rfind("torus", 0) == 0) {
        Vec3f c(pos.x(), pos.y(), 0);
        c = c.normalized() * 2;
        truth = pos - c;
      } else truth = Vec3f(pos.x(), pos.y(), 0);
      if (!(truth.dot(Vec3f(float(p->second.x()), float(p->second.y()), float(p->second.z()))) > 0)) ++cgalIn;
    }
    fmt::print("| {} | {} ({:.2f} s) | {} | {} ({:.2f} s) |\n", name, inward(g.normals), tOurs, o3d, cgalIn, tC);
  }
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--k") && i + 1 < argc) opt.k = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--reps") && i + 1 < argc) opt.reps = std::max(1, std::atoi(argv[++i]));
    else if (!std::strcmp(argv[i], "--no-open3d-orient")) opt.open3dOrient = false;
    else files.push_back(argv[i]);
  }
  for (const auto& f : files) {
    HybridModel m = readModel(f);
    m.attributes.normals = false;
    benchCloud(f.substr(f.find_last_of('/') + 1), m, opt);
  }
  orientationShapes(opt);
  return 0;
}
