// The module's functions: files, the §6.1 geometry, the §3 extractions, rendering (§4-§6.2),
// image metrics (§7) and threads. Keywords of the option structs come from the option tables
// (options.h); the GIL is released during every long call.
#include "functions.h"

#include <memory>
#include <set>

#include "arrays.h"
#include "linesurf/core/parallel.h"
#include "linesurf/eval/image_metrics.h"
#include "linesurf/surface/surface_error.h"
#include "linesurf/extract/contour.h"
#include "linesurf/extract/curvature_lines.h"
#include "linesurf/extract/feature_lines.h"
#include "linesurf/extract/eps_delta.h"
#include "linesurf/extract/shape_approx.h"
#include "linesurf/extract/verify.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_frame.h"
#include "linesurf/io/atomic_file.h"
#include "linesurf/io/model_io.h"
#include "linesurf/lod/lod.h"
#include "linesurf/geometry/noise.h"
#include "linesurf/pipeline/render_job.h"
#include "linesurf/pipeline/verify_job.h"
#include "linesurf/render/drawing.h"
#include "linesurf/render/renderer.h"
#include "linesurf/surface/mesh_extract.h"
#include "linesurf/surface/mls.h"
#include "model.h"
#include "options.h"

namespace linesurf::python {

namespace {

/// A SurfaceError as a dict: figures in object units and relative to eps_ref and the diagonal.
py::dict surfaceErrorDict(const SurfaceError& e) {
  auto figures = [&](const SurfaceErrorFigures& f) {
    py::dict d;
    d["samples"] = f.samples, d["failed_reference"] = f.failedReference, d["failed_model"] = f.failedModel;
    d["rms"] = f.rms, d["p99"] = f.p99, d["max"] = f.max, d["mean"] = f.mean;
    d["rms_eps_ref"] = f.rms / e.epsilonRef, d["p99_eps_ref"] = f.p99 / e.epsilonRef, d["max_eps_ref"] = f.max / e.epsilonRef;
    d["rms_diagonal"] = f.rms / e.diagonal, d["p99_diagonal"] = f.p99 / e.diagonal, d["max_diagonal"] = f.max / e.diagonal;
    return d;
  };
  py::dict d = figures(e.both);
  d["from_reference"] = figures(e.fromReference);
  d["from_model"] = figures(e.fromModel);
  d["reference"] = e.meshReference ? "mesh" : "cloud";
  d["reference_spacing"] = e.referenceSpacing, d["eps_ref"] = e.epsilonRef, d["diagonal"] = e.diagonal;
  d["failures"] = e.failures();
  return d;
}

// ---------------------------------------------------------------------------------------------
// Options from keywords (names: keywordName of the fields).

template <typename E>
E enumFrom(const std::string& value, const char* field, std::initializer_list<std::pair<const char*, E>> names) {
  std::string choices;
  for (auto& [n, e] : names) {
    if (value == n) return e;
    if (!choices.empty()) choices += ", ";
    choices += n;
  }
  throwBadOption(field, "expected one of " + choices + ", got '" + value + "'");
}

GeometryOptions geometryOptions(int k, bool recompute, bool orient, float penalty, const std::string& side,
                                const std::vector<float>& viewpoint) {
  GeometryOptions o;
  o.k = k;
  o.recomputeNormals = recompute;
  o.orientNormals = orient;
  o.orientationPenalty = penalty;
  std::initializer_list<std::pair<const char*, OrientSide>> sides = {{"auto", OrientSide::Auto},
                                                                     {"outward", OrientSide::Outward},
                                                                     {"up", OrientSide::Up},
                                                                     {"towards", OrientSide::Towards},
                                                                     {"away-from", OrientSide::AwayFrom}};
  o.orient = enumFrom<OrientSide>(side, "orient", sides);
  if (viewpoint.size() != 3) throwBadOption("viewpoint", "expected 3 numbers x y z, got " + std::to_string(viewpoint.size()));
  o.viewpoint = Vec3f(viewpoint[0], viewpoint[1], viewpoint[2]);
  validate(o);
  return o;
}

py::object namespaceOf(py::dict d) { return py::module_::import("types").attr("SimpleNamespace")(**d); }

py::dict geometryDict(const PointGeometry& g) {
  py::dict d;
  const size_t n = g.size();
  const int k = g.k;
  auto nb = newArray<int64_t>({py::ssize_t(n), k});
  auto nd = newArray<float>({py::ssize_t(n), k});
  for (size_t i = 0; i < n * size_t(k); ++i) {
    const uint32_t j = g.neighbours[i];
    nb.mutable_data()[i] = j == PointGeometry::kNoNeighbour ? -1 : int64_t(j);
    nd.mutable_data()[i] = g.neighbourDistances[i];
  }
  d["k"] = k;
  d["neighbours"] = nb;
  d["neighbour_distances"] = nd;
  d["normals"] = vec3Array(n, [&](size_t i) { return g.normals[i]; });
  d["eigenvalues"] = vec3Array(n, [&](size_t i) { return g.eigenvalues[i]; });
  d["surface_variation"] = floatVector(g.surfaceVariation);
  d["spacing"] = floatVector(g.spacing);
  d["average_spacing"] = g.averageSpacing;
  auto flags = newArray<uint8_t>({py::ssize_t(n)});
  if (n) std::memcpy(flags.mutable_data(), g.flags.data(), n);
  d["flags"] = flags;
  d["orientation_flips"] = g.orientationFlips;
  if (!g.delaunayOffsets.empty()) {
    auto off = newArray<int64_t>({py::ssize_t(g.delaunayOffsets.size())});
    for (size_t i = 0; i < g.delaunayOffsets.size(); ++i) off.mutable_data()[i] = g.delaunayOffsets[i];
    auto idx = newArray<int64_t>({py::ssize_t(g.delaunayIndices.size())});
    for (size_t i = 0; i < g.delaunayIndices.size(); ++i) idx.mutable_data()[i] = g.delaunayIndices[i];
    d["delaunay_offsets"] = off;
    d["delaunay_indices"] = idx;
  }
  if (g.kMin.size() == n && n) {
    d["k_min"] = floatVector(g.kMin);
    d["k_max"] = floatVector(g.kMax);
    d["min_curvature_dir"] = vec3Array(n, [&](size_t i) { return g.minCurvatureDir[i]; });
    d["max_curvature_dir"] = vec3Array(n, [&](size_t i) { return g.maxCurvatureDir[i]; });
  }
  return d;
}

/// Whether prepareForRendering would change the model (it is copied only then).
bool needsPreparation(const HybridModel& m, float radiusScale) {
  if (radiusScale != 1.0f) return true;
  if (!m.points.empty() && (!m.attributes.normals || !m.attributes.radii)) return true;
  for (const Point& p : m.points)
    if (p.radius == 0.0f) return true;
  for (const Segment& s : m.segments)
    if (s.radius == 0.0f) return true;
  return false;
}

// The §6.1 fields the point extractions take as keywords (as the CLI's extract commands).
const std::set<std::string> kExtractGeometry = {"k", "recomputeNormals", "orientationPenalty", "orient", "viewpoint"};
const std::set<std::string> kShapeGeometry = {"k", "recomputeNormals", "orientationPenalty", "orient", "viewpoint", "curvature"};

std::unique_ptr<ThreadLimit>& threadLimit() {
  static std::unique_ptr<ThreadLimit> limit;
  return limit;
}

}  // namespace

void bindFunctions(py::module_& m) {
  // --- files ----------------------------------------------------------------------------------
  m.def(
      "read",
      [](const std::string& path) {
        py::gil_scoped_release release;
        return readModel(path);
      },
      py::arg("path"),
      "Reads a point cloud or hybrid model (.ply, .xyz; a mesh file gives its vertices) as a Model.\n"
      "Raises FileFormatError (an OSError) with the CLI's one-line message on a bad file.");
  m.def(
      "read_mesh",
      [](const std::string& path) {
        py::gil_scoped_release release;
        return readMesh(path);
      },
      py::arg("path"), "Reads a triangle mesh (.ply with faces, .obj with optional .mtl texture) as a Mesh.");
  m.def(
      "write",
      [](const std::string& path, py::object obj, bool ascii) {
        WriteOptions wo;
        if (ascii) wo.encoding = PlyEncoding::Ascii;
        if (py::isinstance<TriangleMesh>(obj)) {
          const TriangleMesh& mesh = obj.cast<const TriangleMesh&>();
          py::gil_scoped_release release;
          writeMesh(path, mesh, wo);
          return;
        }
        ModelArg a = modelArg(obj);
        py::gil_scoped_release release;
        writeModel(path, *a.model, wo);
      },
      py::arg("path"), py::arg("model"), py::kw_only(), py::arg("ascii") = false,
      "Writes a Model (or an (N, 3) points array) as .ply / .xyz, or a Mesh as .ply / .obj. The file is\n"
      "written to a temporary file and renamed into place.");

  // --- geometry (§6.1) ------------------------------------------------------------------------
  m.def(
      "geometry",
      [](py::object model, int k, bool recompute_normals, bool orient_normals, float orientation_penalty,
         const std::string& orient, const std::vector<float>& viewpoint, bool delaunay_neighbours, bool curvature,
         const std::string& curvature_fit) {
        ModelArg a = modelArg(model);
        GeometryOptions o = geometryOptions(k, recompute_normals, orient_normals, orientation_penalty, orient, viewpoint);
        o.delaunayNeighbours = delaunay_neighbours || curvature;
        o.curvature = curvature;
        o.curvatureFit = enumFrom<CurvatureFit>(curvature_fit, "curvatureFit",
                                                {{"taubin", CurvatureFit::Taubin}, {"quadric", CurvatureFit::Quadric}});
        PointGeometry g;
        {
          py::gil_scoped_release release;
          g = computePointGeometry(*a.model, o);
        }
        return namespaceOf(geometryDict(g));
      },
      py::arg("model"), py::kw_only(), py::arg("k") = GeometryOptions{}.k, py::arg("recompute_normals") = GeometryOptions{}.recomputeNormals,
      py::arg("orient_normals") = GeometryOptions{}.orientNormals, py::arg("orientation_penalty") = GeometryOptions{}.orientationPenalty,
      py::arg("orient") = "auto", py::arg("viewpoint") = std::vector<float>{0, 0, 0}, py::arg("delaunay_neighbours") = false,
      py::arg("curvature") = false, py::arg("curvature_fit") = "taubin",
      R"doc(The §6.1 geometry of a point cloud (a Model or an (N, 3) array), computed once:

neighbours (N, k) int64 (exact kNN, nearest first, -1 padded), neighbour_distances (N, k),
normals (N, 3) unit, MST-oriented (kept from the model unless recompute_normals), eigenvalues
(N, 3), surface_variation (N,), spacing (N,) and average_spacing, flags (N,) uint8; with
delaunay_neighbours: delaunay_offsets / delaunay_indices (CSR); with curvature: k_min, k_max
(N,), min_curvature_dir, max_curvature_dir (N, 3). Returned as a SimpleNamespace.)doc");
  m.def(
      "estimate_noise",
      [](py::object model, int samples, int max_neighbours, float footprint) {
        ModelArg a = modelArg(model);
        NoiseOptions o;
        o.samples = samples, o.maxNeighbours = max_neighbours, o.footprint = footprint;
        validate(o);
        NoiseEstimate e;
        {
          py::gil_scoped_release release;
          e = estimateNoise(*a.model, o);
        }
        py::dict d;
        d["sigma"] = e.sigma, d["lower_quartile"] = e.lowerQuartile, d["upper_quartile"] = e.upperQuartile;
        d["samples"] = e.samples, d["fitted"] = e.fitted, d["unresolved"] = e.unresolved;
        d["median_neighbours"] = e.medianNeighbours;
        return namespaceOf(d);
      },
      py::arg("model"), py::kw_only(), py::arg("samples") = NoiseOptions{}.samples,
      py::arg("max_neighbours") = NoiseOptions{}.maxNeighbours, py::arg("footprint") = NoiseOptions{}.footprint,
      R"doc(The noise of a scan along its normals (a Model or an (N, 3) array) = `linesurf info`'s noise line:
the median over `samples` points of the residual of a quadric height fit over neighbourhoods grown
until they are `footprint` times wider than the residual. Returns a namespace: sigma (object
units), lower_quartile, upper_quartile, samples, fitted, unresolved, median_neighbours.)doc");
  // --- the MLS surface (§9.1) ----------------------------------------------------------------
  m.def(
      "mls_project",
      [](py::object model, py::object points, float support_scale, bool curvature, bool robust) {
        ModelArg a = modelArg(model);
        MlsOptions o;
        o.supportScale = support_scale;
        o.robust = robust;
        validate(o);
        const FloatArray q = floatArray(points, "points", {3});
        const size_t n = size_t(q.n);
        std::vector<MlsProjection> moved(n);
        std::vector<MlsCurvature> bend(curvature ? n : 0);
        {
          py::gil_scoped_release release;
          const MlsSurface surface(*a.model, o);
          parallelForRange(0, n, [&](size_t b, size_t e) {
            for (size_t i = b; i < e; ++i) {
              moved[i] = surface.project(Vec3d(q.at(py::ssize_t(i), 0), q.at(py::ssize_t(i), 1), q.at(py::ssize_t(i), 2)));
              if (curvature) bend[i] = surface.curvature(moved[i].point);
            }
          }, 256);
        }
        py::dict d;
        d["points"] = vec3Array(n, [&](size_t i) { return Vec3f(moved[i].point.cast<float>()); });
        d["normals"] = vec3Array(n, [&](size_t i) { return Vec3f(moved[i].normal.cast<float>()); });
        auto ok = py::array_t<bool>(py::ssize_t(n));
        for (size_t i = 0; i < n; ++i) ok.mutable_data()[i] = moved[i].converged;
        d["converged"] = ok;
        if (curvature) {
          std::vector<float> kMin(n), kMax(n);
          for (size_t i = 0; i < n; ++i) kMin[i] = float(bend[i].kMin), kMax[i] = float(bend[i].kMax);
          d["k_min"] = floatVector(kMin), d["k_max"] = floatVector(kMax);
          d["min_curvature_dir"] = vec3Array(n, [&](size_t i) { return Vec3f(bend[i].dirMin.cast<float>()); });
          d["max_curvature_dir"] = vec3Array(n, [&](size_t i) { return Vec3f(bend[i].dirMax.cast<float>()); });
        }
        return namespaceOf(d);
      },
      py::arg("model"), py::arg("points"), py::kw_only(), py::arg("support_scale") = MlsOptions{}.supportScale,
      py::arg("curvature") = false, py::arg("robust") = false,
      "Projects points (N, 3) onto the MLS surface of a model's oriented points and segments (thesis §9.1,\n"
      "Kolluri's IMLS; segments integrated along their length; robust: RIMLS, creases kept): points, normals (N, 3) float32 and\n"
      "converged (N,) bool (a failed projection: the last iterate); with curvature, k_min, k_max (N,) and\n"
      "min_curvature_dir, max_curvature_dir (N, 3) of the surface there. A SimpleNamespace.");
  m.def("_mesh_options", [] {
    py::list l;
    optionSpecs(l, MeshOptions{});
    return l;
  });
  m.def(
      "_mesh",
      [](py::object model, py::dict options, double max_mb) {
        py::dict kw(options);
        MeshOptions o;
        applyOptions(kw, o);
        rejectUnknown(kw);
        validate(o);
        const Budget budget(max_mb, "max_mb");
        ModelArg a = modelArg(model);
        TriangleMesh mesh;
        {
          py::gil_scoped_release release;
          mesh = extractMesh(*a.model, o, nullptr, budget);
        }
        auto faces = newArray<int64_t>({py::ssize_t(mesh.faces.size()), 3});
        for (size_t i = 0; i < mesh.faces.size(); ++i)
          for (int k = 0; k < 3; ++k) faces.mutable_data()[3 * i + size_t(k)] = mesh.faces[i][size_t(k)];
        return py::make_tuple(vec3Array(mesh.positions.size(), [&](size_t i) { return mesh.positions[i]; }), faces);
      },
      py::arg("model"), py::arg("options") = py::dict(), py::arg("max_mb") = 4096.0,
      "A triangle mesh of the MLS surface of a model's oriented points and segments (thesis §9.1; =\n"
      "`linesurf mesh`): (vertices (V, 3) float32, faces (F, 3) int64), wound so that normals face where the\n"
      "model's do; open where the data is open. Refused (ValueError) when it needs more than max_mb MiB.");
  m.def(
      "normals",
      [](py::object model, int k, bool recompute_normals, bool orient_normals, float orientation_penalty,
         const std::string& orient, const std::vector<float>& viewpoint) {
        ModelArg a = modelArg(model);
        GeometryOptions o = geometryOptions(k, recompute_normals, orient_normals, orientation_penalty, orient, viewpoint);
        o.delaunayNeighbours = false;
        o.curvature = false;
        PointGeometry g;
        {
          py::gil_scoped_release release;
          g = computePointGeometry(*a.model, o);
        }
        return vec3Array(g.size(), [&](size_t i) { return g.normals[i]; });
      },
      py::arg("points"), py::kw_only(), py::arg("k") = GeometryOptions{}.k, py::arg("recompute_normals") = GeometryOptions{}.recomputeNormals,
      py::arg("orient_normals") = GeometryOptions{}.orientNormals, py::arg("orientation_penalty") = GeometryOptions{}.orientationPenalty,
      py::arg("orient") = "auto", py::arg("viewpoint") = std::vector<float>{0, 0, 0},
      "Unit normals (N, 3) float32 of a point cloud (Model or (N, 3) array) by PCA over the k nearest\n"
      "neighbours (Hoppe 1992), consistently oriented by a minimum spanning tree (thesis §6.1), each connected\n"
      "component facing the side `orient` chooses: auto (outward for objects, up for terrain), outward, up,\n"
      "towards or away-from `viewpoint` (x, y, z).");
  m.def("_prepare_options", [] {
    py::list l;
    optionSpecs(l, PrepareOptions{});
    return l;
  }, "The keywords of prepare() from the option tables.");
  m.def(
      "_prepare",
      [](py::object model, py::dict options) {
        py::dict kw(options);
        PrepareOptions o;
        applyOptions(kw, o);
        rejectUnknown(kw);
        validate(o);
        ModelArg a = modelArg(model);
        HybridModel out = *a.model;
        py::gil_scoped_release release;
        prepareForRendering(out, o);
        return out;
      },
      py::arg("model"), py::arg("options") = py::dict(),
      "A copy of the model ready to render: normals and radii of raw scans from the §6.1 geometry\n"
      "(kept when present), radii times radius_scale; what render() does on every call otherwise.");

  // --- extraction (§3) ------------------------------------------------------------------------
  m.def("_extract_eps_delta_options", [] {
    py::list l;
    optionSpecs(l, EpsDeltaOptions{});
    optionSpecs(l, GeometryOptions{}, kExtractGeometry);
    return l;
  });
  m.def(
      "_extract_eps_delta",
      [](py::object model, py::dict options) {
        py::dict kw(options);
        EpsDeltaOptions o;
        GeometryOptions go;
        applyOptions(kw, o);
        applyOptions(kw, go, kExtractGeometry);
        rejectUnknown(kw);
        go.curvature = false;  // §3.1 needs normals, Delaunay neighbours and spacing only
        validate(o);
        validate(go);
        ModelArg a = modelArg(model, "cloud");
        if (!a.model->segments.empty()) throwBadOption("model", "already holds segments; extraction needs a point cloud");
        EpsDeltaStats st;
        HybridModel out;
        {
          py::gil_scoped_release release;
          PointGeometry geo = computePointGeometry(*a.model, go);
          out = extractEpsDelta(*a.model, geo, o, &st);
        }
        out.comments.push_back(std::string("eps-delta: normals=") +
                               (a.model->attributes.normals && !go.recomputeNormals ? "file" : "computed"));
        py::dict stats;
        stats["input_points"] = st.inputPoints, stats["kept_points"] = st.keptPoints, stats["segments"] = st.segments;
        stats["replaced_points"] = st.replacedPoints, stats["epsilon"] = st.epsilon, stats["delta"] = st.delta;
        stats["data_reduction"] = st.dataReduction(), stats["seed_directions"] = st.seedDirections;
        stats["candidate_directions"] = st.candidateDirections, stats["noise_sigma"] = st.noiseSigma;
        py::dict r;
        r["model"] = out;
        r["stats"] = stats;
        return namespaceOf(r);
      },
      py::arg("cloud"), py::arg("options") = py::dict(),
      R"doc((epsilon, delta) error-bounded line segment extraction, thesis §3.1 (= `linesurf extract eps-delta`).

epsilon: distance tolerance (0: epsilon_relative x average spacing); delta: bound on 1 - n_i.n_j.
Returns a namespace with model (the hybrid Model) and stats (dict: input_points, kept_points,
segments, replaced_points, epsilon, delta, data_reduction, ...). provenance=True records the
replaced points (needed by verify()).)doc");
  m.def("_extract_shape_approx_options", [] {
    py::list l;
    optionSpecs(l, ShapeApproxOptions{});
    optionSpecs(l, GeometryOptions{}, kShapeGeometry);
    return l;
  });
  m.def(
      "_extract_shape_approx",
      [](py::object model, py::dict options) {
        py::dict kw(options);
        ShapeApproxOptions o;
        GeometryOptions go;
        applyOptions(kw, o);
        applyOptions(kw, go, kShapeGeometry);
        rejectUnknown(kw);
        validate(o);
        validate(go);
        ModelArg a = modelArg(model, "cloud");
        if (!a.model->segments.empty()) throwBadOption("model", "already holds segments; extraction needs a point cloud");
        if (a.model->points.empty()) throwBadOption("model", "holds no points");
        ShapeApproxStats st;
        HybridModel out;
        Clustering c;
        {
          py::gil_scoped_release release;
          PointGeometry geo = computePointGeometry(*a.model, go);
          c = clusterShapeApprox(geo, o);
          out = extractShapeApprox(*a.model, geo, c, o, &st);
        }
        py::dict stats;
        stats["input_points"] = st.inputPoints, stats["clusters"] = st.clusters, stats["segments"] = st.segments;
        stats["points_kept"] = st.pointsKept, stats["points_replaced"] = st.pointsReplaced;
        stats["clusters_with_segments"] = st.clustersWithSegments, stats["data_reduction"] = st.dataReduction();
        auto labels = newArray<int64_t>({py::ssize_t(c.labels.size())});
        for (size_t i = 0; i < c.labels.size(); ++i) labels.mutable_data()[i] = c.labels[i];
        py::dict r;
        r["model"] = out;
        r["stats"] = stats;
        r["labels"] = labels;
        return namespaceOf(r);
      },
      py::arg("cloud"), py::arg("options") = py::dict(),
      R"doc(Shape-approximation extraction, thesis §3.2 (= `linesurf extract shape-approx`).

method: "greedy" (§3.2.3.1) or "hierarchical" (§3.2.3.2) normal-variation clustering with
tolerance delta_n on ||n(C) - n_j||^2. Returns a namespace with model, stats (dict: clusters,
segments, points_kept, points_replaced, ...) and labels (N,) int64 cluster ids.)doc");
  m.def("_extract_curvature_lines_options", [] {
    py::list l;
    optionSpecs(l, CurvatureLineOptions{});
    optionSpecs(l, GeometryOptions{}, kExtractGeometry);
    return l;
  });
  m.def(
      "_extract_curvature_lines",
      [](py::object model, py::dict options) {
        py::dict kw(options);
        CurvatureLineOptions o;
        GeometryOptions go;
        applyOptions(kw, o);
        applyOptions(kw, go, kExtractGeometry);
        rejectUnknown(kw);
        go.curvature = false;  // the MLS surface gives the curvature; the Delaunay stars are the field's graph
        validate(o);
        validate(go);
        ModelArg a = modelArg(model, "cloud");
        if (!a.model->segments.empty()) throwBadOption("model", "already holds segments; extraction needs a point cloud");
        if (a.model->points.empty()) throwBadOption("model", "holds no points");
        CurvatureLineStats st;
        HybridModel out;
        {
          py::gil_scoped_release release;
          PointGeometry geo = computePointGeometry(*a.model, go);
          out = extractCurvatureLines(*a.model, geo, o, &st);
        }
        out.comments.push_back(std::string("curvature-lines: normals=") +
                               (a.model->attributes.normals && !go.recomputeNormals ? "file" : "computed"));
        py::dict stats;
        stats["input_points"] = st.inputPoints, stats["kept_points"] = st.keptPoints, stats["segments"] = st.segments;
        stats["replaced_points"] = st.replacedPoints, stats["lines"] = st.lines, stats["closed_lines"] = st.closedLines;
        stats["short_lines"] = st.shortLines, stats["line_length"] = st.lineLength;
        stats["mean_chain_length"] = st.meanChainLength(), stats["mean_separation"] = st.meanSeparation;
        stats["epsilon"] = st.epsilon, stats["delta"] = st.delta, stats["average_spacing"] = st.averageSpacing;
        stats["data_reduction"] = st.dataReduction(), stats["chain_data_reduction"] = st.chainDataReduction();
        py::dict r;
        r["model"] = out;
        r["stats"] = stats;
        return namespaceOf(r);
      },
      py::arg("cloud"), py::arg("options") = py::dict(),
      R"doc(Lines of curvature traced on the MLS surface, thesis §9.2 (= `linesurf extract curvature-lines`).

family: "min" (the straightest lines), "max" or "both"; separation: the largest line spacing in
average spacings (narrower where the strip would leave epsilon of the surface). Returns a
namespace with model (chains of segments with shared endpoints, plus the points no strip covers)
and stats (dict: lines, segments, kept_points, mean_chain_length, data_reduction, ...).)doc");
  m.def("_extract_features_options", [] {
    py::list l;
    optionSpecs(l, FeatureLineOptions{});
    optionSpecs(l, GeometryOptions{}, kExtractGeometry);
    return l;
  });
  m.def(
      "_extract_features",
      [](py::object model, py::dict options) {
        py::dict kw(options);
        FeatureLineOptions o;
        GeometryOptions go;
        applyOptions(kw, o);
        applyOptions(kw, go, kExtractGeometry);
        rejectUnknown(kw);
        go.curvature = false, go.delaunayNeighbours = false;
        validate(o);
        validate(go);
        ModelArg a = modelArg(model, "cloud");
        if (!a.model->segments.empty()) throwBadOption("model", "already holds segments; feature lines need a point cloud");
        if (a.model->points.empty()) throwBadOption("model", "holds no points");
        FeatureLineStats st;
        HybridModel out;
        {
          py::gil_scoped_release release;
          HybridModel cloud = *a.model;
          if (!cloud.attributes.normals || go.recomputeNormals) {  // the §6.1 normals, as the CLI
            const PointGeometry geo = computePointGeometry(cloud, go);
            for (size_t i = 0; i < cloud.points.size(); ++i) cloud.points[i].normal = geo.normals[i];
            cloud.attributes.normals = true;
          }
          out = extractFeatureLines(cloud, o, &st);
        }
        py::dict stats;
        stats["points"] = st.points, stats["crease_pairs"] = st.creasePairs, stats["samples"] = st.samples;
        stats["polylines"] = st.polylines, stats["segments"] = st.segments, stats["length"] = st.length;
        stats["spacing"] = st.spacing;
        py::dict r;
        r["model"] = out;
        r["stats"] = stats;
        return namespaceOf(r);
      },
      py::arg("cloud"), py::arg("options") = py::dict(),
      R"doc(Feature lines: a cloud's creases as a line model, thesis §9.5 (= `linesurf extract features`).

Pairs of neighbours whose (robust MLS) normals differ by more than `angle` degrees give samples
on the line where their tangent planes meet; chained and simplified into segments. Returns a
namespace with model (segments only; empty when the cloud has no crease) and stats (dict:
crease_pairs, samples, polylines, segments, length, spacing).)doc");
  m.def("_extract_contour_options", [] {
    py::list l;
    optionSpecs(l, ContourOptions{});
    return l;
  });
  m.def(
      "_extract_contour",
      [](const TriangleMesh& mesh, py::dict options) {
        py::dict kw(options);
        ContourOptions o;
        applyOptions(kw, o);
        rejectUnknown(kw);
        validate(o);
        if (mesh.faces.empty()) throwBadOption("mesh", "holds no faces: contour extraction needs a triangle mesh");
        ContourStats st;
        HybridModel out;
        {
          py::gil_scoped_release release;
          out = extractContour(mesh, o, &st);
        }
        py::dict stats;
        stats["triangles"] = st.triangles, stats["segments"] = st.segments, stats["points"] = st.points;
        stats["spacing"] = st.spacing, stats["radius"] = st.radius, stats["degenerate_triangles"] = st.degenerateTriangles;
        stats["mean_edge_length"] = st.meanEdgeLength, stats["spacing_from_diagonal"] = st.spacingFromDiagonal;
        stats["converted_segments"] = st.convertedSegments;
        stats["segments_before_merge"] = st.segmentsBeforeMerge, stats["polylines"] = st.polylines;
        py::dict r;
        r["model"] = out;
        r["stats"] = stats;
        return namespaceOf(r);
      },
      py::arg("mesh"), py::arg("options") = py::dict(),
      R"doc(Contour-plane extraction from a triangle Mesh, thesis §3.3 (= `linesurf extract contour`).

spacing: largest distance d between neighbouring segments (0: spacing_scale x min(mean edge length,
bounding-box diagonal / diagonal_divisions); diagonal_divisions=0: the mean edge alone);
endpoint_normals=False gives the thesis's one normal per segment (the CLI's --flat);
merge_normal_deviation=0 keeps one segment per face and plane (no polyline merging);
point_masses=False leaves the points (all_points, points_below) the thesis's unit splats instead of
weighing the contour length they stand for (Model.point_masses; the CLI's --no-point-masses).
Returns a namespace with model and stats (dict: triangles, segments, points, spacing, radius, ...).)doc");
  m.def(
      "verify",
      [](py::object cloud, const HybridModel& hybrid, std::optional<double> epsilon, std::optional<double> delta,
         std::optional<int> k, bool surface_error) {
        ModelArg a = modelArg(cloud, "cloud");
        RecordedVerifyOptions o;
        o.epsilon = epsilon, o.delta = delta, o.k = k;
        o.surfaceError = surface_error;
        RecordedVerifyResult r;
        {
          py::gil_scoped_release release;
          r = verifyAsRecorded(*a.model, hybrid, "hybrid", o);
        }
        const VerifyReport& v = r.report;
        py::dict d;
        d["ok"] = v.ok(), d["segments"] = v.segments, d["replaced_points"] = v.replacedPoints;
        d["kept_points"] = v.keptPoints, d["distance_violations"] = v.distanceViolations;
        d["normal_violations"] = v.normalViolations, d["bad_segments"] = v.badSegments, d["bad_indices"] = v.badIndices;
        d["replaced_twice"] = v.replacedTwice, d["missing"] = v.missing, d["unmatched_points"] = v.unmatchedPoints;
        d["max_distance"] = v.maxDistance, d["max_normal_deviation"] = v.maxNormalDeviation;
        d["epsilon"] = r.epsilon, d["delta"] = r.delta, d["k"] = r.k, d["messages"] = v.messages;
        d["surface_error"] = r.surface ? py::object(surfaceErrorDict(*r.surface)) : py::object(py::none());
        return d;
      },
      py::arg("cloud"), py::arg("hybrid"), py::kw_only(), py::arg("epsilon") = py::none(), py::arg("delta") = py::none(),
      py::arg("k") = py::none(), py::arg("surface_error") = true,
      "The certificate check of an (epsilon, delta) extraction (= `linesurf verify-extraction`): every\n"
      "replaced point within epsilon of its segment and delta of its anchor normal, every input point\n"
      "kept or replaced once. Tolerances default to those the hybrid records. Returns a dict with 'ok',\n"
      "and 'surface_error' (surface_error()'s dict with its defaults; None with surface_error=False).");
  m.def("_surface_error_options", [] {
    py::list l;
    optionSpecs(l, SurfaceErrorOptions{});
    return l;
  });
  m.def(
      "_surface_error",
      [](py::object reference, py::object model, py::dict options) {
        py::dict kw(options);
        SurfaceErrorOptions o;
        applyOptions(kw, o);
        rejectUnknown(kw);
        validate(o);
        ModelArg b = modelArg(model, "model");
        SurfaceError e;
        if (py::isinstance<TriangleMesh>(reference)) {
          const TriangleMesh& mesh = reference.cast<const TriangleMesh&>();
          py::gil_scoped_release release;
          e = surfaceError(mesh, *b.model, o);
        } else {
          ModelArg a = modelArg(reference, "reference");
          py::gil_scoped_release release;
          e = surfaceError(*a.model, *b.model, o);
        }
        return surfaceErrorDict(e);
      },
      py::arg("reference"), py::arg("model"), py::arg("options") = py::dict(),
      R"doc(The surface error of an extracted model (beyond the thesis; = the surface line of
`linesurf verify-extraction` and the column of `linesurf experiment`): each sample projected onto
the reference's MLS surface (a cloud with normals) or its closest point (a Mesh) and onto the
model's MLS surface, the distance between the two projections; sampled both ways (the reference's
points or vertices, the model's points and points along its segments). Returns a dict: rms, p99,
max, mean (object units), the same over eps_ref (0.05 x the reference's average spacing, a mesh's
mean edge length) and over the model's diagonal, samples, failed_reference, failed_model,
from_reference and from_model (the same per way), eps_ref, reference_spacing, diagonal.)doc");

  // --- rendering (§4-§6.2) --------------------------------------------------------------------
  m.def("_render_options", [] {
    py::list l;
    optionSpecs(l, ViewOptions{});
    optionSpecs(l, RenderOptions{});
    optionSpecs(l, PrepareOptions{});
    optionSpecs(l, DrawingOptions{});
    return l;
  }, "The keywords of render() from the option tables: [{keyword, field, default, help}].");
  m.def(
      "_render",
      [](py::object model, py::dict options, bool depth, bool alpha, bool normal, py::object budget) -> py::object {
        py::dict kw = options;  // the tables take their keywords out of a copy
        kw = py::dict(kw);
        ViewOptions v;
        RenderOptions o;
        PrepareOptions p;
        DrawingOptions dr;
        applyOptions(kw, v);
        applyOptions(kw, o);
        applyOptions(kw, p);
        applyOptions(kw, dr);
        rejectUnknown(kw);
        o.depthBuffer = depth, o.alphaBuffer = alpha, o.normalBuffer = normal;
        o.facingCheck = true;  // warns below, as the CLI does, when the normals face away
        validate(o);
        validate(v);
        validate(p);
        validate(dr);
        const bool drawing = dr.style != DrawStyle::Splat;

        RenderResult r;
        // A str or PathLike naming a .lod file is a hierarchy; anything else goes to modelArg (so a
        // stray string is still the TypeError of a bad model).
        bool isPath = false;
        if (py::isinstance<py::str>(model) || py::hasattr(model, "__fspath__")) {
          const std::string name = py::str(py::module_::import("os").attr("fspath")(model));
          isPath = name.size() >= 4 && name.compare(name.size() - 4, 4, ".lod") == 0;
        }
        if (isPath && drawing) throwBadOption("style", "draws a model's own segments; it does not apply to a .lod hierarchy");
        if (isPath) {
          // A level-of-detail hierarchy (lod_build): the nodes chosen for the view within `budget`
          // splats (None: every leaf, the whole model's picture), as `linesurf render M.lod --budget`.
          const std::string path = py::str(py::module_::import("os").attr("fspath")(model));
          uint64_t b = UINT64_MAX;  // every leaf
          if (!budget.is_none()) {
            // An integer, not a float or a bool that pybind11 would refuse with a RuntimeError.
            if (!py::isinstance<py::int_>(budget) || py::isinstance<py::bool_>(budget))
              throwBadOption("budget", "must be an integer number of splats (None: every leaf)");
            long long n = 0;
            try {
              n = budget.cast<long long>();
            } catch (const py::cast_error&) {
              throwBadOption("budget", "must be at most 1e15 splats");
            }
            if (n < 1) throwBadOption("budget", "must be >= 1 splats (None: every leaf)");
            b = uint64_t(n);
          }
          std::vector<std::string> failures;
          {
            py::gil_scoped_release release;
            if (!lod::isLodFile(path))
              throw Error(Error::Kind::BadInput, path, "", "not a level-of-detail hierarchy (.lod; see lod_build)");
            const lod::LodFile file(path);
            const lod::LodRenderer renderer(file, o, b, p.radiusScale);
            lod::LodFrameResult f = renderer.render(viewCameras(renderer.sphere(), v, file.header().frame).front());
            r = std::move(f.render);
            failures = std::move(f.failures);
          }
          // A node that failed leaves its part of the picture empty, as in the CLI: say which.
          for (const std::string& e : failures)
            PyErr_WarnEx(PyExc_RuntimeWarning, (e + " (not drawn)").c_str(), 1);
        } else {
        if (!budget.is_none()) throwBadOption("budget", "needs a level-of-detail hierarchy (a .lod path; see lod_build)");
        ModelArg a = modelArg(model);
        if (a.model->empty()) throwBadOption("model", "holds no points and no segments");
        if (drawing && a.model->segments.empty() && !dr.silhouettes)
          throwBadOption("style", "the model has no segments and `silhouettes` is off: nothing to draw");
        {
          py::gil_scoped_release release;
          // What `linesurf render` does to a model before drawing it; a copy only when it changes it.
          const ModelFrame frame = normalizingFrame(a.model->bounds());
          if (!frame.identity()) toFrame(a.mutableCopy(), frame);
          if (needsPreparation(*a.model, p.radiusScale)) prepareForRendering(a.mutableCopy(), p);
          if (drawing) {  // as `linesurf render --style`: the strokes over the paper, the splat's buffers
            const DrawingRenderer drawer(*a.model, o, dr);
            Drawing d = drawer.render(viewCameras(drawer.sphere(), v, frame).front());
            r = std::move(d.splat);
            r.color = std::move(d.image);
            if (!depth) r.depth.reset();
            if (!normal) r.normal.reset();
          } else {
            Renderer renderer(*a.model, o);
            r = renderer.render(viewCameras(renderer.sphere(), v, frame).front());
          }
        }
        }
        if (const std::string w = backFacingWarning(r.stats, isPath ? std::string(py::str(py::module_::import("os").attr("fspath")(model))) : "the model"); !w.empty())
          if (PyErr_WarnEx(PyExc_UserWarning, w.c_str(), 1) < 0) throw py::error_already_set();
        py::array_t<uint8_t> color = rgba8(r.color);
        if (!depth && !alpha && !normal) return color;
        py::dict d;
        d["color"] = color;
        if (r.depth) {
          auto dz = channels(*r.depth, 0, 1);
          for (size_t i = 0; i < r.depth->pixels.size(); ++i)
            if (!(r.depth->pixels[i].w() > 0)) dz.mutable_data()[i] = 0;
          d["depth"] = dz;
        }
        if (r.alpha) d["alpha"] = channels(*r.alpha, 0, 1);
        if (r.normal) d["normal"] = channels(*r.normal, 0, 3);
        return d;
      },
      py::arg("model"), py::arg("options") = py::dict(), py::arg("depth") = false, py::arg("alpha") = false,
      py::arg("normal") = false, py::arg("budget") = py::none(),
      R"doc(Renders a point or hybrid model by EWA splatting (thesis §4-§6.2) = `linesurf render`.
A path to a level-of-detail hierarchy (lod_build) draws at most `budget` splats a view.

Returns an (H, W, 4) uint8 RGBA array, or, when depth/alpha/normal is requested, a dict with
'color' and the requested (H, W) float32 'depth' (linear depth, 0 where empty), (H, W) 'alpha',
(H, W, 3) 'normal' ((n+1)/2). Camera: an orbit view (azimuth, elevation, distance, zoom, fov,
up_axis) auto-framed on the bounding sphere, or look-at (eye, target, up). Raw scans get normals
and radii from the §6.1 geometry (k) on every call; prepare() once for repeated renders. The
keywords are the fields of ViewOptions, RenderOptions, PrepareOptions and DrawingOptions (the option
tables, pipeline/option_tables.h); size = (width, height); style='lines' or 'hatch' draws the
model's segments as ink strokes (§9.4, §9.5) instead of splatting them. The GIL is released.)doc");

  m.def(
      "lod_build",
      [](py::object model, const std::string& path, int leaf_size, int grid, int k) -> py::dict {
        lod::BuildOptions b;
        b.leafSize = leaf_size, b.grid = grid;
        lod::validate(b);
        PrepareOptions p;
        p.k = k;
        validate(p);
        ModelArg a = modelArg(model);
        if (a.model->empty()) throwBadOption("model", "holds no points and no segments");
        if (a.model->texture) throw Error(Error::Kind::BadInput, path, "", "textured models have no level-of-detail form yet");
        lod::BuildReport rep;
        {
          py::gil_scoped_release release;
          // The model as render() draws it: in its normalising frame, prepared; then the octree.
          HybridModel m = *a.model;
          const ModelFrame frame = normalizingFrame(m.bounds());
          toFrame(m, frame);
          prepareForRendering(m, p);
          writeFileAtomically(path, lod::buildLod(m, frame, b, &rep));
        }
        py::dict d;
        d["primitives"] = rep.primitives;
        d["representatives"] = rep.representatives;
        d["nodes"] = rep.nodes;
        d["leaves"] = rep.leaves;
        d["depth"] = rep.depth;
        d["bytes"] = rep.bytes;
        d["hierarchy"] = rep.hierarchyId;
        return d;
      },
      py::arg("model"), py::arg("path"), py::kw_only(), py::arg("leaf_size") = lod::BuildOptions{}.leafSize,
      py::arg("grid") = lod::BuildOptions{}.grid, py::arg("k") = PrepareOptions{}.k,
      "Writes the level-of-detail hierarchy of a point or hybrid model to `path` (.lod) =\n"
      "`linesurf lod build`: an octree whose leaves hold the originals and whose inner nodes hold\n"
      "merged splats; render(path, budget=N) draws at most N splats a view. Returns a dict of counts.");

  // --- images (§7) ----------------------------------------------------------------------------
  m.def(
      "compare",
      [](py::object a, py::object b) {
        Image ia = imageFrom(a, "a"), ib = imageFrom(b, "b");
        if (ia.width != ib.width || ia.height != ib.height)
          throwBadOption("b", "size " + std::to_string(ib.width) + "x" + std::to_string(ib.height) + " differs from a (" +
                                  std::to_string(ia.width) + "x" + std::to_string(ia.height) + ")");
        ImageMetrics mt;
        HoleMap holes;
        {
          py::gil_scoped_release release;
          mt = compareImages(ia, ib);
          holes = holeMap(ia, ib);
        }
        py::dict d;
        d["mse"] = mt.mse, d["psnr"] = mt.psnr, d["nccm"] = mt.nccm, d["ssim"] = mt.ssim;
        d["mean_abs_diff"] = mt.meanAbsDiff, d["std_abs_diff"] = mt.stdAbsDiff, d["max_abs_diff"] = mt.maxAbsDiff;
        d["differing_pixels"] = mt.differingPixels;
        d["holes"] = holes.holes, d["hole_share"] = holes.holeShare(), d["extra_pixels"] = holes.extra;
        return d;
      },
      py::arg("a"), py::arg("b"),
      "Image metrics of thesis §7 (= `linesurf compare`): mse, psnr (inf when identical), nccm, ssim,\n"
      "mean/std/max absolute difference in grey levels, fraction of differing pixels; holes (pixels a\n"
      "covers and b does not: by alpha when both carry it, else against white), hole_share of a's\n"
      "covered pixels, extra_pixels (b only). a and b are (H, W, 3|4) uint8 or float [0, 1] arrays, or\n"
      "image paths; the metrics ignore alpha.");
  m.def(
      "difference_heatmap",
      [](py::object a, py::object b, double saturate) {
        Image ia = imageFrom(a, "a"), ib = imageFrom(b, "b");
        if (ia.width != ib.width || ia.height != ib.height) throwBadOption("b", "size differs from a");
        if (!(saturate > 0) || !std::isfinite(saturate)) throwBadOption("saturate", "must be a finite number > 0");
        return rgba8(differenceHeatmap(ia, ib, saturate));
      },
      py::arg("a"), py::arg("b"), py::kw_only(), py::arg("saturate") = 32.0,
      "Heat-map (H, W, 4) uint8 of the per-pixel maximum channel difference (= compare --diff).");
  m.def(
      "read_image",
      [](const std::string& path) {
        Image img;
        {
          py::gil_scoped_release release;
          img = readImage(path);
        }
        return rgba8(img);
      },
      py::arg("path"), "Reads a PNG/JPEG/BMP/TGA image as an (H, W, 4) uint8 array.");
  m.def(
      "write_png",
      [](const std::string& path, py::object image) {
        Image img = imageFrom(image, "image");
        py::array a = py::array::ensure(image);
        const bool withAlpha = a && a.ndim() == 3 && a.shape(2) == 4;
        py::gil_scoped_release release;
        writePng(path, img, withAlpha);
      },
      py::arg("path"), py::arg("image"), "Writes an (H, W, 3|4) uint8 or float [0, 1] array as an 8-bit PNG.");

  // --- threads --------------------------------------------------------------------------------
  m.def(
      "set_threads",
      [](int threads) {
        if (threads < 0 || threads > 1024) throwBadOption("threads", "must be in [0, 1024] (0 = all cores)");
        threadLimit().reset();
        if (threads > 0) threadLimit() = std::make_unique<ThreadLimit>(threads);
      },
      py::arg("threads"),
      "Limits the worker threads of every later call (0 = all cores). Results do not depend on it.");
  m.def("thread_count", &currentThreadCount, "Number of worker threads calls use now.");}

}  // namespace linesurf::python
