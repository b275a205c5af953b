#include "export.hpp"

#include <charconv>
#include <cstdio>
#include <algorithm>
#include <sys/stat.h>

#include "export_formats.hpp"
#include "scene.hpp"
#include "shapes.hpp"

namespace liedyn {

std::optional<ExportFormat> parse_export_format(std::string_view name) {
  if (name == "gltf") return ExportFormat::kGltf;
  if (name == "obj") return ExportFormat::kObj;
  if (name == "vtk") return ExportFormat::kVtk;
  return std::nullopt;
}

const char* export_format_name(ExportFormat format) {
  switch (format) {
    case ExportFormat::kGltf: return "gltf";
    case ExportFormat::kObj: return "obj";
    case ExportFormat::kVtk: return "vtk";
  }
  return "?";
}

std::string frame_file_name(int frame_number, const char* extension) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%06d.%s", frame_number, extension);
  return name;
}

void append_float(std::string& out, float x) {
  char text[32];
  const auto end = std::to_chars(text, text + sizeof text, x).ptr;
  out.append(text, end);
}

std::string shortest(double x) {
  char text[32];
  return std::string(text, std::to_chars(text, text + sizeof text, x).ptr);
}

std::string one_line(const std::string& text) {
  std::string out = text;
  for (char& c : out) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = ' ';
  }
  return out;
}

namespace {

// An OBJ object name: one word (OBJ splits at white space), so every space or control
// character becomes '_'.
std::string obj_name(const std::string& name) {
  std::string out = name.empty() ? "_" : name;
  for (char& c : out) {
    if (static_cast<unsigned char>(c) <= 0x20 || c == 0x7f) c = '_';
  }
  return out;
}

// "o NAME", its vertices and its faces (OBJ indices are global and from 1: `base` vertices
// precede these).
void append_obj_object(std::string& out, const std::string& name, const std::vector<Vector3>& vertices,
                       const TriangleMesh& faces, std::size_t base) {
  out += "o " + obj_name(name) + "\n";
  for (const Vector3& v : vertices) {
    out += 'v';
    for (int c = 0; c < 3; ++c) {
      out += ' ';
      append_float(out, static_cast<float>(v[c]));
    }
    out += '\n';
  }
  for (const auto& t : faces.triangles) {
    out += 'f';
    for (const int i : t) {
      out += ' ';
      out += std::to_string(base + static_cast<std::size_t>(i) + 1);
    }
    out += '\n';
  }
}

}  // namespace

std::vector<std::string> write_obj(const ExportJob& job, OutputFolder& folder) {
  const RecordedRun& run = job.run;
  const ExportGeometry& g = job.geometry;
  const std::string title = one_line(run.shapes.value("title", run.dir.string()));
  // Colliders first, the same text in every file: their indices do not depend on the frame.
  std::string colliders;
  std::size_t collider_vertices = 0;
  for (const ExportGeometry::Obstacle& c : g.colliders) {
    append_obj_object(colliders, c.name, c.mesh.vertices, c.mesh, collider_vertices);
    collider_vertices += c.mesh.vertices.size();
  }
  std::vector<std::string> names;
  std::string text;
  std::vector<Vector3> world;
  for (std::size_t k = 0; k < job.frames.size(); ++k) {
    const std::size_t f = job.frames[k];
    text = "# liedyn export of " + title + ": frame " + std::to_string(run.frame_numbers[f]) + " (" +
           std::to_string(k + 1) + " of " + std::to_string(job.frames.size()) + "), time " + shortest(run.times[f]) +
           " s; world coordinates, m\n";
    text += colliders;
    std::size_t base = collider_vertices;
    for (const ExportGeometry::Body& body : g.bodies) {
      const RigidPose pose = row_pose(run, f, body.row);
      world.clear();
      for (const Vector3& v : body.mesh.vertices) world.push_back(pose.apply(v));
      append_obj_object(text, body.name, world, body.mesh, base);
      base += world.size();
    }
    for (const ExportGeometry::Rod& rod : g.rods) {
      // A tube about the nodes: a ring at each, closed by a half sphere at either end.
      TubeShape tube{{}, rod.radius};
      for (int i = 0; i < rod.nodes; ++i) tube.polyline.push_back(node_position(run, f, rod.first_node_row + i));
      const TriangleMesh mesh = tessellate(tube, job.options.rod_segments);
      append_obj_object(text, rod.name, mesh.vertices, mesh, base);
      base += mesh.vertices.size();
    }
    names.push_back(frame_file_name(run.frame_numbers[f], "obj"));
    folder.add(names.back()) << text;
    folder.finish(names.back());
  }
  return names;
}

ExportSummary write_export(const std::filesystem::path& run_dir, const ExportOptions& options) {
  if (options.every < 1 || options.segments < 3 || options.rod_segments < 3) {
    throw std::invalid_argument("write_export: every ≥ 1, segments ≥ 3 and rod_segments ≥ 3");
  }
  const RecordedRun run = read_recorded_run(run_dir);
  const ExportGeometry geometry = export_geometry(run, options.segments);
  ExportJob job{run, geometry, {}, options};
  for (std::size_t f = 0; f < run.frame_count(); f += static_cast<std::size_t>(options.every)) job.frames.push_back(f);
  if (job.frames.back() + 1 != run.frame_count()) job.frames.push_back(run.frame_count() - 1);

  const char* format = export_format_name(options.format);
  ExportSummary summary;
  summary.dir = options.out.empty() ? run_dir / (std::string("export-") + format) : options.out;
  OutputFolder folder(summary.dir, std::string("export --format ") + format, nullptr);
  std::vector<std::string> names;
  // The files of an earlier export of this format, which this one replaces: its fixed names
  // and its frame files (frame_ + digits + the extension).
  std::vector<std::string> fixed;
  const char* frame_extension = nullptr;
  switch (options.format) {
    case ExportFormat::kGltf:
      names = write_gltf(job, folder);
      fixed = {"run.glb"};
      break;
    case ExportFormat::kObj:
      names = write_obj(job, folder);
      frame_extension = ".obj";
      break;
    case ExportFormat::kVtk:
      names = write_vtk(job, folder);
      fixed = {"colliders.vtp", "run.pvd"};
      frame_extension = ".vtp";
      break;
  }
  folder.commit([&](const std::string& name) {
    if (std::find(fixed.begin(), fixed.end(), name) != fixed.end()) return true;
    if (frame_extension == nullptr || name.rfind("frame_", 0) != 0) return false;
    const std::size_t dot = name.find('.', 6);
    return dot > 6 && dot != std::string::npos && name.substr(dot) == frame_extension &&
           std::all_of(name.begin() + 6, name.begin() + static_cast<std::ptrdiff_t>(dot),
                       [](char c) { return c >= '0' && c <= '9'; });
  });

  summary.files = static_cast<int>(names.size());
  summary.frames = static_cast<int>(job.frames.size());
  summary.objects = geometry.objects();
  for (const std::string& name : names) {
    struct stat st {};
    if (::stat((summary.dir / name).c_str(), &st) == 0) summary.bytes += static_cast<std::uintmax_t>(st.st_size);
  }
  return summary;
}

}  // namespace liedyn
