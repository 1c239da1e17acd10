#pragma once
// A random unit-sphere point cloud scaled by `s` (normals, radii 0.12 s), shared by the
// reliability and scale tests.
#include <random>

#include "linesurf/core/model.h"

namespace linesurf::test {

inline HybridModel randomSphere(int n, float s, bool attributes, unsigned seed) {
  HybridModel m;
  std::mt19937 rng(seed);
  std::normal_distribution<float> g;
  for (int i = 0; i < n; ++i) {
    Vec3f dir(g(rng), g(rng), g(rng));
    dir.normalize();
    Point p;
    p.position = dir * s;
    p.normal = dir;
    p.radius = 0.12f * s;
    m.points.push_back(p);
  }
  m.attributes.normals = m.attributes.radii = attributes;
  return m;
}

}  // namespace linesurf::test
