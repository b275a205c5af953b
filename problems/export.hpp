#pragma once
// `liedyn export RUN_DIR --format gltf|obj|vtk [--every N] [--out DIR]`: a recorded run
// (problems/recorded_run.hpp) as files other programs open — Blender, three.js or any glTF
// viewer; anything that reads OBJ; ParaView. Every format draws the same meshes
// (problems/export_geometry.hpp: shapes.json's shapes through tessellate(), rods of their
// radius, planes as a finite square 3× the size of everything that moves); they differ in
// what they add:
//
//  gltf  run.glb, glTF 2.0 binary (written with tinygltf): one node per body (its mesh in the
//        body frame, animated translation and rotation), one per rod edge (a cylinder of the
//        rod's radius and unit length along its local z, which the edge frame turns onto the
//        edge: animated translation = the midpoint of its two nodes, rotation = the edge frame
//        R_j (R_j e_z is the tangent, lib/rod.hpp), scale (1, 1, edge length) so a stretched
//        rod stays joined — a sheared edge's ends leave its nodes by the shear), one static
//        node per collider, named as the objects ("rod/edge j" for edges). One animation,
//        LINEAR samplers over the exported times (s). Rotations are made to take the short
//        way between frames (q and −q are one rotation; slerp follows the sign).
//  obj   frame_NNNNNN.obj per exported frame (NNNNNN = the run's frame number): every
//        object's mesh in world coordinates as an "o NAME" group (rods as tubes about their
//        nodes), colliders in every file; a comment names the run, the frame and the time.
//  vtk   frame_NNNNNN.vtp per exported frame (VTK XML PolyData 0.1, ASCII) and run.pvd (a
//        ParaView Collection, timestep = time, s): rods as polylines through their nodes,
//        bodies as triangles, with point fields
//          velocity     m/s, by central differences of the points' positions between the
//                       exported frames (one-sided at the first and last; 0 for one frame),
//          penetration  m, how deep the point is inside a collider, signed (> 0 inside,
//                       < 0 the clearance): rod nodes  radius − φ(x), body vertices −φ(x),
//                       the largest over the colliders, φ their signed distance
//                       (lib/sdf.hpp). Left out of the files when the run has no collider or
//                       a mesh collider: shapes.json has a mesh's triangles but not the
//                       solid it was drawn from (tori, cylinders and links are meshes
//                       there) nor the grid the simulation used, so no distance would be
//                       the simulation's,
//          object_id    the object's place in shapes.json: bodies, then rods, then colliders,
//          radius       m, a rod's radius (0 on bodies): ParaView's Tube filter draws it.
//        Colliders, which do not move, are colliders.vtp (with object_id), outside the series.
//
// `every` exports every every-th written frame and the last. Files go to DIR (default
// RUN_DIR/export-<format>) as one unit (problems/output_folder.hpp), which replaces the
// frames of an earlier export there; file names are fixed or frame numbers, never names from
// the run (which is untrusted input: names are only written inside the files, sanitised).
// Bad input is a SceneError naming the file, the field or line, and the reason.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string_view>

namespace liedyn {

enum class ExportFormat { kGltf, kObj, kVtk };
std::optional<ExportFormat> parse_export_format(std::string_view name);  // "gltf", "obj", "vtk"
const char* export_format_name(ExportFormat format);

struct ExportOptions {
  ExportFormat format = ExportFormat::kGltf;
  int every = 1;                    // ≥ 1
  std::filesystem::path out;        // empty: RUN_DIR/export-<format>
  int segments = 24;                // around every circle of a tessellated shape (≥ 3)
  int rod_segments = 12;            // around a rod (≥ 3)
};

struct ExportSummary {
  std::filesystem::path dir;  // where the files are
  int files = 0;
  int frames = 0;   // exported
  int objects = 0;  // bodies + rods + colliders
  std::uintmax_t bytes = 0;
};

ExportSummary write_export(const std::filesystem::path& run_dir, const ExportOptions& options);

}  // namespace liedyn
