#pragma once
// A recorded run as meshes and poses, what every export format (problems/export.hpp) draws:
// the one place where shapes.json (problems/shapes.hpp) becomes triangles.
//
//  bodies     their shape in the body frame through tessellate() (problems/shapes.hpp), placed
//             by the shape's "position"/"rotation"; "points" (contact samples) as a small
//             sphere of the sample radius each, "axes" as three slim boxes along +x, +y, +z;
//  rods       node count and radius (their tubes and cylinders are the formats' own);
//  colliders  in world coordinates: plane (a square about the projection of the centre of
//             everything that moves, 3× its size, as the viewer draws it), sphere, box,
//             capsule, tube and mesh, each also as a Collider (lib/sdf.hpp) for its signed
//             distance — except meshes, whose distance is not known (problems/export.hpp).
// Every number is checked (finite, radii positive, indices in range, quaternions of unit
// length): shapes.json and trajectory.csv are untrusted, and a bad value is a SceneError
// naming the file and the field, or the frame and the object.

#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "../lib/mesh_sdf.hpp"
#include "../lib/sdf.hpp"
#include "recorded_run.hpp"

namespace liedyn {

struct RigidPose {
  Vector3 position = Vector3::Zero();
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  // unit
  Vector3 apply(const Vector3& p) const { return position + rotation * p; }
};

struct ExportGeometry {
  struct Body {
    std::string name;
    int row = 0;        // in RecordedRun::rows
    TriangleMesh mesh;  // body frame
  };
  struct Rod {
    std::string name;
    int nodes = 0;
    double radius = 0.0;
    int first_node_row = 0, first_edge_row = 0;  // in RecordedRun::rows
  };
  struct Obstacle {  // a static collider
    std::string name;
    std::string type;   // shapes.json's
    TriangleMesh mesh;  // world
    std::optional<Collider> distance;  // its signed distance (lib/sdf.hpp), when known
  };
  std::vector<Body> bodies;
  std::vector<Rod> rods;
  std::vector<Obstacle> colliders;

  int objects() const { return static_cast<int>(bodies.size() + rods.size() + colliders.size()); }
  // Whether penetration() means something: at least one collider, and every collider's
  // distance known.
  bool penetration_known() const;
  // How deep a ball of radius `radius` (0: a point) about p reaches into the colliders: the
  // largest radius − φ(p) over them, signed (> 0 inside). Needs penetration_known().
  double penetration(const Vector3& p, double radius) const;
};

// Reads the run's shapes; `segments` around every circle (problems/shapes.hpp, tessellate).
ExportGeometry export_geometry(const RecordedRun& run, int segments);

// A body's or an edge's pose at written frame f (unit quaternion: checked by
// export_geometry), a node's position.
RigidPose row_pose(const RecordedRun& run, std::size_t frame, int row);
Vector3 node_position(const RecordedRun& run, std::size_t frame, int row);

}  // namespace liedyn
