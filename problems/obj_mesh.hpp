#pragma once
// Triangle meshes from Wavefront OBJ files (tinyobjloader), for GridSdf (lib/mesh_sdf.hpp).
//
// Only geometry is read: vertex positions (`v x y z`, any `w` ignored) and faces (`f`, the
// vertex index of each corner; texture and normal indices, groups, objects, materials and
// `mtllib` are ignored — no .mtl file is opened). Faces of more than three vertices are
// triangulated by tinyobjloader (a quad v0 v1 v2 v3 becomes two triangles that keep its
// orientation); all shapes (`o`/`g`) go into one mesh, sharing the file's vertex list, so
// indices are the file's (1-based, or negative = relative, in the file; 0-based here).
// Positions are multiplied by `scale`. Lines and points (`l`, `p`) are ignored.
// Topology (closed, oriented, non-degenerate) is checked by GridSdf, not here.

#include <cstdint>
#include <filesystem>

#include "lib/mesh_sdf.hpp"

namespace liedyn {

// Mesh files above this size are refused unread (a 327680-triangle OBJ is ~25 MB).
inline constexpr std::uintmax_t kMaxMeshFileBytes = 512u << 20;

// Reads `file`. Throws std::runtime_error whose message names the file and the reason (and
// the 1-based line, for a NUL byte or a vertex): it does not exist or cannot be read, is not
// a regular file (a FIFO, socket or device) or is larger than kMaxMeshFileBytes, it holds a
// NUL byte (not a text file), a vertex line has fewer than three coordinates or one that is
// not a finite decimal number ("abc", "nan", "inf", "1e999", "0x10", "1.5.3": tinyobjloader
// itself would read most of these as 0 without an error), a coordinate times scale is not
// finite, tinyobjloader reports a parse error (e.g. a face index 0 or a non-numeric face
// index), a face index is outside the file's vertices, a face has fewer than 3 vertices, or
// the file has no faces. Only x y z of a vertex line are read (a w or vertex colours after
// them are ignored). Throws std::invalid_argument if scale is not finite or ≤ 0. In a scene
// (problems/scene.cpp) the message becomes the reason of a SceneError on the collider's
// "file" field.
TriangleMesh load_obj_mesh(const std::filesystem::path& file, double scale = 1.0);

}  // namespace liedyn
