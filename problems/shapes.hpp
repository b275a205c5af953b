#pragma once
// What it takes to draw a run (`liedyn view`, problems/view.hpp; any other viewer): every
// body's shape, every rod's node count and radius, every static collider, as JSON. Written
// beside the trajectory as shapes.json by every run that writes one (problems/run.hpp).
//
//   {"title", "time_step", "trajectory_every",
//    "bodies":    [{"name", "shape": SHAPE}],              in trajectory.csv's order
//    "rods":      [{"name", "nodes", "radius"}],
//    "colliders": [COLLIDER]}
// SHAPE, in the body frame (origin: the centre of mass), from the body's solid if it has one,
// else its contact samples, else a triad the size of its inertia ellipsoid:
//   {"type": "box", "half_extents", "rounding"} | {"type": "sphere", "radius"}
//   {"type": "capsule", "radius", "half_length"} | {"type": "cylinder", "radius", "half_length"}
//   {"type": "torus", "major_radius", "minor_radius"} | {"type": "mesh", "vertices", "triangles"}
//   {"type": "points", "points", "radius"} | {"type": "axes", "size"}
// (a chain link is a mesh of its surface; axes along z, tori in the xy plane), with
// "position" and "rotation" (qw, qx, qy, qz) when the solid's frame is not the body's.
// COLLIDER, in world coordinates, with "name" and "inside" (the solid is outside the surface):
//   {"type": "plane", "point", "normal"} | {"type": "sphere", "center", "radius"}
//   {"type": "box", "center", "half_extents", "rotation" (qw, qx, qy, qz), "rounding"}
//   {"type": "capsule", "a", "b", "radius"} | {"type": "tube", "points", "radius"}
//   {"type": "mesh", "vertices", "triangles"}            (also tori, cylinders and links)
// Vectors are flat arrays of numbers ("points", "vertices": x0, y0, z0, x1, …).

#include <nlohmann/json_fwd.hpp>

#include "../lib/mesh_sdf.hpp"
#include "scene.hpp"

namespace liedyn {

nlohmann::ordered_json scene_shapes(const Scene& scene, int trajectory_every);

// The surface of a collider's shape in its own frame, as a closed mesh (outward normals by the
// right-hand rule): `segments` around every circle (a rounded box's edges and a hemisphere's
// latitudes: a quarter of that, at least 2 steps). Every shape but the plane, which has none
// (std::invalid_argument): the shapes a viewer has no primitive for (tori, links, cylinders)
// in shapes.json, and every shape of an export (problems/export_geometry.hpp). A tube is a
// capsule about each point's ring, turned without twist; at a sharp bend its rings may cross.
TriangleMesh tessellate(const Shape& shape, int segments);

}  // namespace liedyn
