#pragma once
/// Synthetic open scenes with ground truth, for measuring normal orientation where no closed
/// object gives an inside and an outside: each point is the first hit of a scanner ray, carries
/// the true surface normal turned to the side the scanner saw, and a class.
///
/// Three scenes (z up, metres, near the origin; the geometry is the same for every seed, the
/// seed picks the rays):
/// - Terrain, an airborne LiDAR strip: 200 m x 200 m ([-100, 100]^2) of rolling ground (three
///   sinusoids, slopes under 20 degrees, heights within +-5 m), 12 buildings (boxes 8-30 m wide
///   at any rotation about z; 6 with flat roofs 4-20 m high, 6 gabled with eaves 4-12 m and
///   pitches of 25-40 degrees, ridges under 19 m; heights above the highest ground under the
///   footprint) and 40 tree crowns (ellipsoids the pulse penetrates: a return at an exponentially
///   distributed depth, mean 2 m, or none, so crowns are volumes of scattered points with ground
///   below them). Rays come from a flight line along y at x = 0, z = 500, each within 20 degrees
///   of nadir: a target on z = 0 is drawn uniformly in the area, then the sensor position on the
///   line among those that see it within 20 degrees. Walls get points from the tilt, at lower
///   density; shadows behind buildings and the ground under roofs get none.
/// - Room, a terrestrial scanner inside: the box [-4, 4] x [-3, 3] x [0, 3] (floor = ground,
///   ceiling = roof, four walls) with a table (1.6 x 0.9 x 0.75 m), a cabinet (0.6 x 1.2 x 2 m)
///   and a crate (0.5 m cube): boxes standing on the floor at rotations of 20, -10 and 35 degrees,
///   class object. The scanner at (0.8, -0.6, 1.5); rays uniform over the sphere.
/// - Facade, mobile mapping along a street: the facade plane y = 0, x in [-30, 30], z in [0, 15]
///   (the building behind it, y > 0), with window recesses 0.2 m deep (glass at y = 0.2; the
///   reveals, sills and lintels are wall too): 20 bays of 3 m from x = -30 and 4 storeys of
///   3.6 m from z = 0, a window 1.4 m wide in the middle of each bay, from 0.9 to 2.5 m above
///   its storey's floor. 5 balconies (class object) stand out 1.4 m (y in [-1.4, 0]): a slab
///   0.2 m thick below a storey's floor and a balustrade panel 1 m high at its front edge. The
///   street z = 0 lies in front (y in [-15, 0], class ground). The sensor moves along
///   x in [-30, 30] at y = -10, z = 2.5; each ray lies within 70 degrees of +y (uniform over
///   that cone); rays into the sky or past the ends are drawn again.
///
/// The true normal is the analytic one, unit, turned to face the ray (up for ground and roofs,
/// outward for walls and objects, into the room indoors); for vegetation it is the direction
/// back to the ray's origin. Point i depends only on (seed, i) (a ray that hits nothing in the
/// scene is drawn again from (seed, i, attempt)), so any N is generated in chunks, with the
/// same points for any thread count.
#include <cstdint>
#include <filesystem>
#include <vector>

#include "linesurf/core/math.h"

namespace linesurf::ooc {

enum class SceneKind { Terrain, Room, Facade };

enum SceneClass : uint8_t { kSceneGround = 0, kSceneRoof = 1, kSceneWall = 2, kSceneVegetation = 3, kSceneObject = 4 };

struct SyntheticSceneOptions {
  SceneKind kind = SceneKind::Terrain;
  uint64_t count = 1000000;
  uint64_t seed = 1;
  /// Gaussian noise along the true normal, sigma as a fraction of the expected spacing
  /// sqrt(A / count), A the scene's nominal sampled area: terrain 200 x 200 = 40000 m^2 (the
  /// footprint), room 2 (8 x 6 + 8 x 3 + 6 x 3) = 180 m^2 (its inner surface), facade
  /// 60 x 15 + 60 x 10 = 1500 m^2 (the facade and the street between it and the sensor line).
  double noise = 0.1;
};

struct ScenePoint {
  Vec3f position;
  Vec3f normal;  ///< unit, true, facing the scanner's side
  uint8_t cls;   ///< a SceneClass
};

/// Points [first, first + n) of the scene.
void syntheticScenePoints(const SyntheticSceneOptions& o, uint64_t first, size_t n, std::vector<ScenePoint>& out);

/// Where the scanner is: room: the scanner position inside; facade: a point on the street side
/// (the middle of the sensor line); terrain: a point high above the centre (the middle of the
/// flight line).
Vec3d sceneSensor(const SyntheticSceneOptions& o);

/// The expected spacing sqrt(A / count) that `noise` is a fraction of (A as above).
double sceneSpacing(const SyntheticSceneOptions& o);

/// "terrain", "room" or "facade".
const char* sceneName(SceneKind kind);

/// Writes the scene's x y z as binary little-endian PLY (in chunks of 1 M points, as
/// writeSyntheticScan does); with a `truth` path also a second PLY of the same points with
/// nx ny nz (the true normals) and a float property `class` (the SceneClass).
void writeSyntheticScene(const std::filesystem::path& path, const SyntheticSceneOptions& o,
                         const std::filesystem::path& truth = {});

}  // namespace linesurf::ooc
