#pragma once
/// Sampled analytic shapes with known normals and curvature, for tests, benchmarks and demos.
/// All samplers are deterministic for a given seed. Normals are exact and outward.
#include <cstdint>

#include "linesurf/core/model.h"

namespace linesurf::shapes {

struct SampleOptions {
  float noise = 0;          ///< Gaussian position noise, as a fraction of the nominal spacing
  bool irregular = false;   ///< uniform random sampling instead of a regular grid
  uint64_t seed = 1;
  Color color = Color(0.8f, 0.8f, 0.8f, 1.0f);
};

/// Plane z = 0 over [-w/2, w/2] x [-h/2, h/2], nx x ny samples, normal +z; radius = spacing.
HybridModel plane(float width, float height, int nx, int ny, const SampleOptions& o = {});
/// Sphere of radius r about the origin, n samples (Fibonacci lattice when regular).
HybridModel sphere(float r, int n, const SampleOptions& o = {});
/// Open cylinder of radius r along z from -h/2 to h/2; nAround x nAlong grid samples.
HybridModel cylinder(float r, float h, int nAround, int nAlong, const SampleOptions& o = {});
/// Torus about z with major radius R and minor radius r; nMajor x nMinor grid samples.
HybridModel torus(float R, float r, int nMajor, int nMinor, const SampleOptions& o = {});

/// Two sheets W = 0.5 wide and 1 long meeting along the y axis (|y| <= 0.5, the crease) at the
/// interior dihedral angle `theta` (degrees), on jittered grids of `spacing`, with Gaussian
/// noise of `noise` x spacing along the exact normals; `ridge` points the normals out of the
/// wedge (a convex crease), else into it (a valley).
HybridModel fold(double theta, double spacing, double noise, bool ridge, uint64_t seed);
/// Triangulated sphere (icosphere with `subdivisions` levels), outward normals per vertex.
TriangleMesh sphereMesh(float r, int subdivisions);
/// Planar grid mesh in z = 0 over [0,1]^2 with per-corner uv = (x, y); nx x ny quads.
TriangleMesh gridMesh(int nx, int ny);

}  // namespace linesurf::shapes
