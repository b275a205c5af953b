// VTK XML PolyData series for ParaView (problems/export.hpp): "VTK File Formats", XML
// PolyData (version 0.1, ASCII data arrays: a layout every VTK since 5 reads) and the
// Collection (.pvd) file that orders the pieces in time.
#include "export_formats.hpp"

namespace liedyn {
namespace {

// An XML comment's text: no "--" (nor a final '-') may occur in it, and no control character.
std::string xml_comment(const std::string& text) {
  std::string out;
  for (const char c : one_line(text)) {
    if (c == '-' && !out.empty() && out.back() == '-') out += ' ';
    out += c;
  }
  if (!out.empty() && out.back() == '-') out += ' ';
  return out;
}

// The points of one exported frame: every body's vertices (world), then every rod's nodes.
std::vector<Vector3> frame_points(const ExportJob& job, std::size_t f) {
  std::vector<Vector3> points;
  for (const ExportGeometry::Body& body : job.geometry.bodies) {
    const RigidPose pose = row_pose(job.run, f, body.row);
    for (const Vector3& v : body.mesh.vertices) points.push_back(pose.apply(v));
  }
  for (const ExportGeometry::Rod& rod : job.geometry.rods) {
    for (int i = 0; i < rod.nodes; ++i) points.push_back(node_position(job.run, f, rod.first_node_row + i));
  }
  return points;
}

class ArrayWriter {
 public:
  explicit ArrayWriter(std::string& out) : out_(out) {}
  void begin(const char* type, const char* name, int components) {
    out_ += "        <DataArray type=\"";
    out_ += type;
    out_ += '"';
    if (name != nullptr) {
      out_ += " Name=\"";
      out_ += name;
      out_ += '"';
    }
    out_ += " NumberOfComponents=\"" + std::to_string(components) + "\" format=\"ascii\">\n";
    count_ = 0;
  }
  void value(float x) {
    separate();
    append_float(out_, x);
  }
  void integer(std::size_t x) {
    separate();
    out_ += std::to_string(x);
  }
  void end() { out_ += "\n        </DataArray>\n"; }

 private:
  // Twelve values to a line: short lines, few of them.
  void separate() {
    out_ += count_ == 0 ? "          " : count_ % 12 == 0 ? "\n          " : " ";
    ++count_;
  }
  std::string& out_;
  std::size_t count_ = 0;
};

void piece_header(std::string& out, std::size_t points, std::size_t lines, std::size_t polys) {
  out += "<?xml version=\"1.0\"?>\n";
  out += "<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\" header_type=\"UInt32\">\n";
  out += "  <PolyData>\n";
  out += "    <Piece NumberOfPoints=\"" + std::to_string(points) + "\" NumberOfVerts=\"0\" NumberOfLines=\"" +
         std::to_string(lines) + "\" NumberOfStrips=\"0\" NumberOfPolys=\"" + std::to_string(polys) + "\">\n";
}

void piece_footer(std::string& out) { out += "    </Piece>\n  </PolyData>\n</VTKFile>\n"; }

void write_points(std::string& out, const std::vector<Vector3>& points) {
  ArrayWriter a(out);
  out += "      <Points>\n";
  a.begin("Float32", nullptr, 3);
  for (const Vector3& p : points) {
    for (int c = 0; c < 3; ++c) a.value(static_cast<float>(p[c]));
  }
  a.end();
  out += "      </Points>\n";
}

// Cells as VTK lists them: every cell's point ids in one array, and where each cell ends.
void write_cells(std::string& out, const char* element, const std::vector<std::vector<std::size_t>>& cells) {
  ArrayWriter a(out);
  out += std::string("      <") + element + ">\n";
  a.begin("Int64", "connectivity", 1);
  for (const auto& cell : cells) {
    for (const std::size_t id : cell) a.integer(id);
  }
  a.end();
  a.begin("Int64", "offsets", 1);
  std::size_t end = 0;
  for (const auto& cell : cells) a.integer(end += cell.size());
  a.end();
  out += std::string("      </") + element + ">\n";
}

// The triangles of the bodies (point ids from 0: bodies come first) and one polyline per rod.
struct Cells {
  std::vector<std::vector<std::size_t>> triangles, lines;
};
Cells frame_cells(const ExportGeometry& g) {
  Cells cells;
  std::size_t base = 0;
  for (const ExportGeometry::Body& body : g.bodies) {
    for (const auto& t : body.mesh.triangles) {
      cells.triangles.push_back({base + std::size_t(t[0]), base + std::size_t(t[1]), base + std::size_t(t[2])});
    }
    base += body.mesh.vertices.size();
  }
  for (const ExportGeometry::Rod& rod : g.rods) {
    std::vector<std::size_t> line;
    for (int i = 0; i < rod.nodes; ++i) line.push_back(base++);
    cells.lines.push_back(std::move(line));
  }
  return cells;
}

std::string colliders_file(const ExportGeometry& g) {
  std::vector<Vector3> points;
  std::vector<std::vector<std::size_t>> triangles;
  std::vector<std::size_t> ids;
  for (std::size_t c = 0; c < g.colliders.size(); ++c) {
    const TriangleMesh& mesh = g.colliders[c].mesh;
    const std::size_t base = points.size();
    points.insert(points.end(), mesh.vertices.begin(), mesh.vertices.end());
    ids.insert(ids.end(), mesh.vertices.size(), g.bodies.size() + g.rods.size() + c);
    for (const auto& t : mesh.triangles) {
      triangles.push_back({base + std::size_t(t[0]), base + std::size_t(t[1]), base + std::size_t(t[2])});
    }
  }
  std::string out;
  piece_header(out, points.size(), 0, triangles.size());
  out += "      <PointData Scalars=\"object_id\">\n";
  ArrayWriter a(out);
  a.begin("Int32", "object_id", 1);
  for (const std::size_t id : ids) a.integer(id);
  a.end();
  out += "      </PointData>\n";
  write_points(out, points);
  write_cells(out, "Polys", triangles);
  piece_footer(out);
  return out;
}

}  // namespace

std::vector<std::string> write_vtk(const ExportJob& job, OutputFolder& folder) {
  const RecordedRun& run = job.run;
  const ExportGeometry& g = job.geometry;
  const Cells cells = frame_cells(g);
  // Per point: its object and radius (the same every frame).
  std::vector<std::size_t> object_id;
  std::vector<double> radius;
  for (std::size_t b = 0; b < g.bodies.size(); ++b) {
    object_id.insert(object_id.end(), g.bodies[b].mesh.vertices.size(), b);
    radius.insert(radius.end(), g.bodies[b].mesh.vertices.size(), 0.0);
  }
  for (std::size_t r = 0; r < g.rods.size(); ++r) {
    object_id.insert(object_id.end(), static_cast<std::size_t>(g.rods[r].nodes), g.bodies.size() + r);
    radius.insert(radius.end(), static_cast<std::size_t>(g.rods[r].nodes), g.rods[r].radius);
  }
  const bool penetration = g.penetration_known();

  std::vector<std::string> names;
  const std::size_t frames = job.frames.size();
  // Positions at the exported frames k − 1, k, k + 1 (computed once each).
  std::vector<Vector3> before, now = frame_points(job, job.frames[0]), after;
  std::string out;
  for (std::size_t k = 0; k < frames; ++k) {
    const std::size_t f = job.frames[k];
    after = k + 1 < frames ? frame_points(job, job.frames[k + 1]) : std::vector<Vector3>();
    // Velocity: central differences between the exported frames, one-sided at the first
    // and the last; none (0) with one frame.
    const std::vector<Vector3>& from = k > 0 ? before : now;
    const std::vector<Vector3>& to = k + 1 < frames ? after : now;
    const double dt = run.times[job.frames[k + 1 < frames ? k + 1 : k]] - run.times[job.frames[k > 0 ? k - 1 : k]];

    out.clear();
    piece_header(out, now.size(), cells.lines.size(), cells.triangles.size());
    out += "      <FieldData>\n        <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" "
           "format=\"ascii\">\n          ";
    out += shortest(run.times[f]) + "\n        </DataArray>\n      </FieldData>\n";
    out += penetration ? "      <PointData Scalars=\"penetration\" Vectors=\"velocity\">\n"
                       : "      <PointData Scalars=\"object_id\" Vectors=\"velocity\">\n";
    ArrayWriter a(out);
    a.begin("Float32", "velocity", 3);
    for (std::size_t i = 0; i < now.size(); ++i) {
      const Vector3 v = dt > 0.0 ? Vector3((to[i] - from[i]) / dt) : Vector3::Zero();
      for (int c = 0; c < 3; ++c) a.value(static_cast<float>(v[c]));
    }
    a.end();
    if (penetration) {
      a.begin("Float32", "penetration", 1);
      for (std::size_t i = 0; i < now.size(); ++i) a.value(static_cast<float>(g.penetration(now[i], radius[i])));
      a.end();
    }
    a.begin("Int32", "object_id", 1);
    for (const std::size_t id : object_id) a.integer(id);
    a.end();
    a.begin("Float32", "radius", 1);
    for (const double r : radius) a.value(static_cast<float>(r));
    a.end();
    out += "      </PointData>\n";
    write_points(out, now);
    write_cells(out, "Lines", cells.lines);
    write_cells(out, "Polys", cells.triangles);
    piece_footer(out);
    names.push_back(frame_file_name(run.frame_numbers[f], "vtp"));
    folder.add(names.back()) << out;
    folder.finish(names.back());
    before = std::move(now);
    now = std::move(after);
  }

  // The collection: every frame's file at its time, and which object each object_id is.
  std::string pvd = "<?xml version=\"1.0\"?>\n";
  pvd += "<!-- liedyn export of " + xml_comment(run.shapes.value("title", run.dir.string())) + " -->\n";
  std::vector<std::string> objects;
  for (const auto& b : g.bodies) objects.push_back("body " + b.name);
  for (const auto& r : g.rods) objects.push_back("rod " + r.name);
  for (const auto& c : g.colliders) objects.push_back("collider " + c.name + " (colliders.vtp)");
  for (std::size_t i = 0; i < objects.size(); ++i) {
    pvd += "<!-- object_id " + std::to_string(i) + ": " + xml_comment(objects[i]) + " -->\n";
  }
  if (!penetration) {
    pvd += g.colliders.empty() ? "<!-- no penetration field: the run has no collider -->\n"
                               : "<!-- no penetration field: a mesh collider's signed distance is not known -->\n";
  }
  pvd += "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n  <Collection>\n";
  for (std::size_t k = 0; k < frames; ++k) {
    pvd += "    <DataSet timestep=\"" + shortest(run.times[job.frames[k]]) + "\" group=\"\" part=\"0\" file=\"" + names[k] + "\"/>\n";
  }
  pvd += "  </Collection>\n</VTKFile>\n";
  if (!g.colliders.empty()) {
    names.push_back("colliders.vtp");
    folder.add(names.back()) << colliders_file(g);
  }
  names.push_back("run.pvd");
  folder.add(names.back()) << pvd;
  return names;
}

}  // namespace liedyn
