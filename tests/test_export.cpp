// `liedyn export` (problems/export.hpp): runs simulated into temporary folders and exported,
// the files read back here — the glb by hand (header, chunks) and with tinygltf's reader, the
// VTK files with a small XML reading of their own, the OBJ files as text — and compared with
// trajectory.csv; runs written by hand for the penetration field; bad input. Real consumers
// (three.js's GLTFLoader in Chromium, VTK's reader) are ctests of their own
// (tests/CMakeLists.txt, scripts/export/).

#include <gtest/gtest.h>
#include <tiny_gltf.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "cli_fixture.hpp"

namespace liedyn::export_tests {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kScenes = std::string(LIEDYN_SOURCE_DIR) + "/problems/scenes/";
const std::string kExportScene = std::string(LIEDYN_SOURCE_DIR) + "/tests/data/export_scene.json";

// trajectory.csv as the test reads it: per frame its time, per (frame, object, kind, index)
// the 7 pose values (nodes: 3).
struct Trajectory {
  std::vector<int> frames;
  std::map<int, double> time;
  std::map<std::tuple<int, std::string, std::string, int>, std::vector<double>> pose;

  explicit Trajectory(const fs::path& file) {
    std::istringstream in(test::read_file(file));
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line)) {
      std::vector<std::string> f;
      std::stringstream s(line);
      for (std::string v; std::getline(s, v, ',');) f.push_back(v);
      if (line.back() == ',') f.emplace_back();
      const int frame = std::stoi(f[0]);
      if (frames.empty() || frames.back() != frame) frames.push_back(frame);
      time[frame] = std::stod(f[1]);
      std::vector<double> values;
      for (std::size_t c = 5; c < f.size() && !f[c].empty(); ++c) values.push_back(std::stod(f[c]));
      pose[{frame, f[2], f[3], std::stoi(f[4])}] = values;
    }
  }
  const std::vector<double>& at(int frame, const std::string& object, const std::string& kind, int index = 0) const {
    return pose.at({frame, object, kind, index});
  }
};

Eigen::Vector3d xyz(const std::vector<double>& p) { return {p[0], p[1], p[2]}; }
Eigen::Quaterniond rotation(const std::vector<double>& p) { return Eigen::Quaterniond(p[3], p[4], p[5], p[6]); }

std::uint32_t u32(const std::string& bytes, std::size_t at) {
  std::uint32_t v = 0;
  std::memcpy(&v, bytes.data() + at, 4);  // GLB is little-endian, as this machine
  return v;
}

// The float values of an accessor (tightly packed, as the export writes them).
std::vector<float> floats(const tinygltf::Model& m, int accessor) {
  const tinygltf::Accessor& a = m.accessors.at(static_cast<std::size_t>(accessor));
  const tinygltf::BufferView& v = m.bufferViews.at(static_cast<std::size_t>(a.bufferView));
  EXPECT_EQ(a.componentType, TINYGLTF_COMPONENT_TYPE_FLOAT);
  const std::size_t n = a.count * static_cast<std::size_t>(tinygltf::GetNumComponentsInType(static_cast<std::uint32_t>(a.type)));
  std::vector<float> out(n);
  std::memcpy(out.data(), m.buffers.at(static_cast<std::size_t>(v.buffer)).data.data() + v.byteOffset + a.byteOffset,
              n * sizeof(float));
  return out;
}

// The value of attribute NAME="…" in an XML tag's text; empty when it has none.
std::string xml_attribute(const std::string& tag, const std::string& name) {
  const std::string key = " " + name + "=\"";
  const std::size_t at = tag.find(key);
  if (at == std::string::npos) return "";
  const std::size_t from = at + key.size();
  return tag.substr(from, tag.find('"', from) - from);
}

// Every occurrence of `from` in `text` replaced by `to`.
std::string replace_all(std::string text, const std::string& from, const std::string& to) {
  for (std::size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size())) {
    text.replace(at, from.size(), to);
  }
  return text;
}

// A VTK XML file scanned by hand: the Piece's counts, and each DataArray's numbers by name
// ("Points" for the points' array, which has none).
struct VtkPiece {
  std::map<std::string, std::string> piece;  // NumberOfPoints, …
  std::map<std::string, std::vector<double>> arrays;
  std::map<std::string, int> components;

  explicit VtkPiece(const fs::path& file) {
    const std::string text = test::read_file(file);
    EXPECT_NE(text.find(R"(<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian")"), std::string::npos)
        << file;
    const std::size_t piece_at = text.find("<Piece ");
    EXPECT_NE(piece_at, std::string::npos) << file;
    if (piece_at == std::string::npos) return;
    const std::string piece_tag = text.substr(piece_at, text.find('>', piece_at) - piece_at);
    for (const char* name : {"NumberOfPoints", "NumberOfVerts", "NumberOfLines", "NumberOfStrips", "NumberOfPolys"}) {
      if (const std::string value = xml_attribute(piece_tag, name); !value.empty()) piece[name] = value;
    }
    // Lines and Polys each have a "connectivity" and "offsets": keyed "Lines/connectivity" ….
    const std::size_t points_at = text.find("<Points>"), lines_at = text.find("<Lines>"), polys_at = text.find("<Polys>");
    for (std::size_t at = text.find("<DataArray "); at != std::string::npos; at = text.find("<DataArray ", at + 1)) {
      const std::size_t body = text.find('>', at) + 1, close = text.find("</DataArray>", body);
      const std::string head = text.substr(at, body - at);
      std::string key = xml_attribute(head, "Name");
      if (key.empty() && at > points_at) key = "Points";
      if (polys_at != std::string::npos && at > polys_at) {
        key = "Polys/" + key;
      } else if (lines_at != std::string::npos && at > lines_at) {
        key = "Lines/" + key;
      }
      std::vector<double> values;
      std::istringstream in(text.substr(body, close - body));
      for (double v; in >> v;) values.push_back(v);
      arrays[key] = values;
      const std::string components_of = xml_attribute(head, "NumberOfComponents");
      components[key] = components_of.empty() ? 1 : std::stoi(components_of);
    }
  }
  std::size_t points() const { return std::stoul(piece.at("NumberOfPoints")); }
  Eigen::Vector3d vector(const std::string& name, std::size_t i) const {
    const std::vector<double>& a = arrays.at(name);
    return {a.at(3 * i), a.at(3 * i + 1), a.at(3 * i + 2)};
  }
};

// The (timestep, file) entries of a .pvd.
std::vector<std::pair<double, std::string>> pvd_entries(const fs::path& file) {
  const std::string text = test::read_file(file);
  std::vector<std::pair<double, std::string>> out;
  for (std::size_t at = text.find("<DataSet "); at != std::string::npos; at = text.find("<DataSet ", at + 1)) {
    const std::string tag = text.substr(at, text.find('>', at) - at);
    EXPECT_EQ(xml_attribute(tag, "group"), "") << tag;
    EXPECT_EQ(xml_attribute(tag, "part"), "0") << tag;
    out.emplace_back(std::stod(xml_attribute(tag, "timestep")), xml_attribute(tag, "file"));
  }
  return out;
}

// The names in `dir` that begin with `prefix` and end with `suffix`, sorted.
std::vector<std::string> files_named(const fs::path& dir, const std::string& prefix, const std::string& suffix = "") {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name.size() >= prefix.size() + suffix.size() && name.compare(0, prefix.size(), prefix) == 0 &&
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0) {
      names.push_back(name);
    }
  }
  std::sort(names.begin(), names.end());
  return names;
}

class ExportCli : public test::CliFixture {
 protected:
  ExportCli() : CliFixture("liedyn_export_") {}

  // A short spinning, drifting body (the butterfly bolt, 20 frames, given a velocity).
  void simulate_body(const std::string& out) {
    const Result r = run({"simulate", kScenes + "butterfly_bolt.json", "--set", "frames=20", "--set",
                          "bodies.0.linear_velocity=[0.5, -0.25, 0.2]", "--out", out, "--quiet"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  // A rod dropped on a plane (the coiled rope, short: 12 frames).
  void simulate_rod(const std::string& out) {
    const Result r = run({"simulate", kScenes + "contact/rod_coil.json", "--set", "frames=12", "--out", out, "--quiet"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
};

// ---------------------------------------------------------------------------------------
// glTF binary
// ---------------------------------------------------------------------------------------

// The GLB container as the spec lays it out: a 12-byte header ("glTF", version 2, the file's
// length), then chunks of (length, type, data), a JSON chunk first and a BIN chunk, every
// length a multiple of 4 and the chunks filling the file exactly.
json check_glb_container(const fs::path& file) {
  const std::string bytes = test::read_file(file);
  EXPECT_GE(bytes.size(), 28u);
  EXPECT_EQ(bytes.substr(0, 4), "glTF");
  EXPECT_EQ(u32(bytes, 4), 2u);
  EXPECT_EQ(u32(bytes, 8), bytes.size());
  EXPECT_EQ(bytes.size() % 4, 0u);
  const std::uint32_t json_length = u32(bytes, 12);
  EXPECT_EQ(u32(bytes, 16), 0x4E4F534Au);  // "JSON"
  EXPECT_EQ(json_length % 4, 0u);
  const std::size_t bin_at = 20 + json_length;
  EXPECT_LE(bin_at + 8, bytes.size());
  const std::uint32_t bin_length = u32(bytes, bin_at);
  EXPECT_EQ(u32(bytes, bin_at + 4), 0x004E4942u);  // "BIN\0"
  EXPECT_EQ(bin_length % 4, 0u);
  EXPECT_EQ(bin_at + 8 + bin_length, bytes.size());
  const json j = json::parse(bytes.substr(20, json_length));  // padded with spaces: still JSON
  EXPECT_LE(j["buffers"][0]["byteLength"].get<std::size_t>(), bin_length);
  EXPECT_GT(j["buffers"][0]["byteLength"].get<std::size_t>() + 4, bin_length);
  return j;
}

tinygltf::Model load_glb(const fs::path& file) {
  tinygltf::TinyGLTF loader;
  tinygltf::Model model;
  std::string error, warning;
  EXPECT_TRUE(loader.LoadBinaryFromFile(&model, &error, &warning, file.string())) << error;
  EXPECT_EQ(error, "");
  EXPECT_EQ(warning, "");
  return model;
}

// Every sampler: `frames` inputs with min and max, LINEAR; rotations of unit length.
void check_animation(const tinygltf::Model& m, std::size_t frames) {
  ASSERT_EQ(m.animations.size(), 1u);
  for (const tinygltf::AnimationChannel& c : m.animations[0].channels) {
    const tinygltf::AnimationSampler& s = m.animations[0].samplers.at(static_cast<std::size_t>(c.sampler));
    const tinygltf::Accessor& input = m.accessors.at(static_cast<std::size_t>(s.input));
    EXPECT_EQ(input.count, frames);
    EXPECT_EQ(input.minValues.size(), 1u);
    EXPECT_EQ(input.maxValues.size(), 1u);
    EXPECT_EQ(s.interpolation, "LINEAR");
    EXPECT_EQ(m.accessors.at(static_cast<std::size_t>(s.output)).count, frames);
    if (c.target_path == "rotation") {
      const std::vector<float> q = floats(m, s.output);
      for (std::size_t k = 0; k < frames; ++k) {
        const double norm = std::sqrt(double(q[4 * k]) * q[4 * k] + double(q[4 * k + 1]) * q[4 * k + 1] +
                                      double(q[4 * k + 2]) * q[4 * k + 2] + double(q[4 * k + 3]) * q[4 * k + 3]);
        EXPECT_LT(std::abs(norm - 1.0), 1e-6) << k;
      }
    }
  }
  for (const tinygltf::Mesh& mesh : m.meshes) {
    for (const tinygltf::Primitive& p : mesh.primitives) {
      const tinygltf::Accessor& position = m.accessors.at(static_cast<std::size_t>(p.attributes.at("POSITION")));
      EXPECT_EQ(position.minValues.size(), 3u) << mesh.name;
      EXPECT_EQ(position.maxValues.size(), 3u) << mesh.name;
    }
  }
}

// The sampler output of `node`'s channel `path`.
std::vector<float> channel(const tinygltf::Model& m, int node, const std::string& path) {
  for (const tinygltf::AnimationChannel& c : m.animations.at(0).channels) {
    if (c.target_node == node && c.target_path == path) {
      return floats(m, m.animations[0].samplers.at(static_cast<std::size_t>(c.sampler)).output);
    }
  }
  ADD_FAILURE() << "no " << path << " channel for node " << node;
  return {};
}

TEST_F(ExportCli, GlbOfABodyHoldsItsPosesAtTheExportedFrames) {
  simulate_body("run");
  const Result e = run({"export", "run", "--format", "gltf", "--every", "3"});
  ASSERT_EQ(e.exit_code, 0) << e.err;
  // 21 written frames (0 … 20): 0, 3, …, 18 and the last.
  EXPECT_NE(e.out.find("export: 1 files, 8 frames, 1 objects"), std::string::npos) << e.out;
  const fs::path glb = dir_ / "run" / "export-gltf" / "run.glb";
  const json j = check_glb_container(glb);
  EXPECT_EQ(j["asset"]["version"], "2.0");
  const tinygltf::Model m = load_glb(glb);
  ASSERT_EQ(m.nodes.size(), 1u);
  EXPECT_EQ(m.nodes[0].name, "bolt");
  check_animation(m, 8);
  const Trajectory t(dir_ / "run" / "trajectory.csv");
  const std::vector<int> exported = {0, 3, 6, 9, 12, 15, 18, 20};
  const std::vector<float> times = floats(m, m.animations[0].samplers[0].input);
  const std::vector<float> x = channel(m, 0, "translation"), q = channel(m, 0, "rotation");
  for (std::size_t k = 0; k < exported.size(); ++k) {
    const int frame = exported[k];
    EXPECT_FLOAT_EQ(times[k], static_cast<float>(t.time.at(frame)));
    const std::vector<double>& pose = t.at(frame, "bolt", "body");
    for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(x[3 * k + c], static_cast<float>(pose[c])) << frame;
    // glTF's order is x, y, z, w; the sign may be flipped to keep the turns short.
    const Eigen::Quaterniond exported_q(q[4 * k + 3], q[4 * k], q[4 * k + 1], q[4 * k + 2]);
    EXPECT_NEAR(std::abs(exported_q.dot(rotation(pose))), 1.0, 1e-6) << frame;
  }
  EXPECT_NE(x[21], x[0]);  // it drifts
}

TEST_F(ExportCli, GlbOfARodOnAPlaneHasANodePerEdgeAtItsMidpoint) {
  simulate_rod("run");
  const Result e = run({"export", "run", "--format", "gltf"});
  ASSERT_EQ(e.exit_code, 0) << e.err;
  const fs::path glb = dir_ / "run" / "export-gltf" / "run.glb";
  check_glb_container(glb);
  const tinygltf::Model m = load_glb(glb);
  // 160 edges and the floor.
  ASSERT_EQ(m.nodes.size(), 161u);
  EXPECT_EQ(m.nodes[0].name, "rope/edge 0");
  EXPECT_EQ(m.nodes[159].name, "rope/edge 159");
  EXPECT_EQ(m.nodes[160].name, "floor");
  EXPECT_GE(m.nodes[160].mesh, 0);  // the floor: a square
  check_animation(m, 13);
  EXPECT_EQ(m.animations[0].channels.size(), 160u * 3);
  const Trajectory t(dir_ / "run" / "trajectory.csv");
  for (const int frame : {0, 7, 12}) {
    for (const int j : {0, 80, 159}) {
      const Eigen::Vector3d mid = 0.5 * (xyz(t.at(frame, "rope", "node", j)) + xyz(t.at(frame, "rope", "node", j + 1)));
      const std::vector<float> x = channel(m, j, "translation"), s = channel(m, j, "scale"), q = channel(m, j, "rotation");
      for (int c = 0; c < 3; ++c) EXPECT_FLOAT_EQ(x[3 * frame + c], static_cast<float>(mid[c])) << frame << " " << j;
      const double length = (xyz(t.at(frame, "rope", "node", j + 1)) - xyz(t.at(frame, "rope", "node", j))).norm();
      EXPECT_FLOAT_EQ(s[3 * frame + 2], static_cast<float>(length));
      // The edge frame's z along the edge: the cylinder lies along it.
      const Eigen::Quaterniond r(q[4 * frame + 3], q[4 * frame], q[4 * frame + 1], q[4 * frame + 2]);
      const Eigen::Vector3d tangent =
          (xyz(t.at(frame, "rope", "node", j + 1)) - xyz(t.at(frame, "rope", "node", j))).normalized();
      EXPECT_GT((r * Eigen::Vector3d::UnitZ()).dot(tangent), 0.99);
      EXPECT_NEAR(std::abs(r.dot(rotation(t.at(frame, "rope", "edge", j)))), 1.0, 1e-6);
    }
  }
}

// ---------------------------------------------------------------------------------------
// VTK PolyData series
// ---------------------------------------------------------------------------------------

TEST_F(ExportCli, VtkSeriesHasBodyVelocitiesByCentralDifferences) {
  simulate_body("run");
  const Result e = run({"export", "run", "--format", "vtk", "--every", "2", "--out", "vtk"});
  ASSERT_EQ(e.exit_code, 0) << e.err;
  const auto entries = pvd_entries(dir_ / "vtk" / "run.pvd");
  ASSERT_EQ(entries.size(), 11u);  // 0, 2, …, 20
  const Trajectory t(dir_ / "run" / "trajectory.csv");
  for (std::size_t k = 0; k < entries.size(); ++k) {
    EXPECT_EQ(entries[k].second, "frame_0000" + std::string(2 * k < 10 ? "0" : "") + std::to_string(2 * k) + ".vtp");
    EXPECT_NEAR(entries[k].first, t.time.at(static_cast<int>(2 * k)), 1e-15);
    if (k > 0) {
      EXPECT_GT(entries[k].first, entries[k - 1].first);
    }
    EXPECT_TRUE(fs::exists(dir_ / "vtk" / entries[k].second));
  }
  EXPECT_FALSE(fs::exists(dir_ / "vtk" / "colliders.vtp"));  // none in this run

  // A vertex of the body: its place in the body frame from frame 0, its world positions at
  // frames 4 and 8 from trajectory.csv, so the velocity at frame 6.
  const VtkPiece first(dir_ / "vtk" / "frame_000000.vtp"), middle(dir_ / "vtk" / "frame_000006.vtp");
  ASSERT_GT(first.points(), 8u);
  EXPECT_EQ(middle.points(), first.points());
  EXPECT_EQ(first.arrays.count("penetration"), 0u);  // no collider: no depth
  EXPECT_EQ(first.arrays.at("object_id").size(), first.points());
  EXPECT_EQ(first.components.at("velocity"), 3);
  for (const std::size_t i : {std::size_t(0), first.points() / 2, first.points() - 1}) {
    const std::vector<double>& p0 = t.at(0, "bolt", "body");
    const Eigen::Vector3d local = rotation(p0).inverse() * (first.vector("Points", i) - xyz(p0));
    const auto world = [&](int frame) {
      const std::vector<double>& p = t.at(frame, "bolt", "body");
      return Eigen::Vector3d(xyz(p) + rotation(p) * local);
    };
    const Eigen::Vector3d v = (world(8) - world(4)) / (t.time.at(8) - t.time.at(4));
    EXPECT_LT((middle.vector("velocity", i) - v).norm(), 1e-5 * (1 + v.norm())) << i;
    EXPECT_LT((middle.vector("Points", i) - world(6)).norm(), 1e-5) << i;
    // One-sided at the ends.
    const VtkPiece last(dir_ / "vtk" / "frame_000020.vtp");
    const Eigen::Vector3d v_end = (world(20) - world(18)) / (t.time.at(20) - t.time.at(18));
    EXPECT_LT((last.vector("velocity", i) - v_end).norm(), 1e-5 * (1 + v_end.norm())) << i;
  }
}

// A run folder written by hand: a rod of two nodes (radius 0.1) above a floor at z = 0 and a
// ball-shaped body, frames at t = 0, 0.5, … moving 0.1 along y per frame.
void write_hand_run(const fs::path& dir, double z0, double z1, const json& colliders, int frames = 2) {
  fs::create_directories(dir);
  json shapes = {{"title", "by hand"},
                 {"bodies", json::array({{{"name", "ball"}, {"shape", {{"type", "sphere"}, {"radius", 0.2}}}}})},
                 {"rods", json::array({{{"name", "stick"}, {"nodes", 2}, {"radius", 0.1}}})},
                 {"colliders", colliders}};
  std::ofstream(dir / "shapes.json") << shapes.dump(1);
  std::ofstream t(dir / "trajectory.csv");
  t << "frame,time,object,kind,index,x,y,z,qw,qx,qy,qz\n";
  for (int frame = 0; frame < frames; ++frame) {
    const double time = 0.5 * frame, shift = 0.1 * frame;
    t << frame << "," << time << ",ball,body,0,5," << shift << ",0.15,1,0,0,0\n";
    t << frame << "," << time << ",stick,node,0,0," << shift << "," << z0 << ",,,,\n";
    t << frame << "," << time << ",stick,node,1,1," << shift << "," << z1 << ",,,,\n";
    t << frame << "," << time << ",stick,edge,0,0.5," << shift << "," << 0.5 * (z0 + z1) << ",0.70710678118654757,0,0.70710678118654746,0\n";
  }
}

TEST_F(ExportCli, PenetrationIsSignedDepthIntoTheColliders) {
  const json floor = json::array({{{"name", "floor"}, {"type", "plane"}, {"point", {0, 0, 0}}, {"normal", {0, 0, 1}}, {"inside", false}}});
  write_hand_run(dir_ / "run", 0.04, 0.3, floor);
  const Result e = run({"export", "run", "--format", "vtk"});
  ASSERT_EQ(e.exit_code, 0) << e.err;
  const fs::path out = dir_ / "run" / "export-vtk";
  const VtkPiece p(out / "frame_000001.vtp");
  // The ball's vertices, then the stick's two nodes.
  const std::size_t n = p.points();
  ASSERT_GT(n, 2u);
  const std::vector<double>& depth = p.arrays.at("penetration");
  EXPECT_NEAR(depth[n - 2], 0.1 - 0.04, 1e-6);  // 6 cm into the floor
  EXPECT_NEAR(depth[n - 1], 0.1 - 0.3, 1e-6);   // 20 cm clear of it
  EXPECT_NEAR(p.arrays.at("radius")[n - 1], 0.1, 1e-7);
  EXPECT_EQ(p.arrays.at("object_id")[n - 1], 1);
  EXPECT_EQ(p.arrays.at("object_id")[0], 0);
  // The ball (radius 0.2 about z = 0.15): its lowest vertex 5 cm deep, its highest 35 cm clear.
  double deepest = -1, shallowest = 1;
  for (std::size_t i = 0; i + 2 < n; ++i) {
    deepest = std::max(deepest, depth[i]);
    shallowest = std::min(shallowest, depth[i]);
    EXPECT_NEAR(depth[i], -p.vector("Points", i).z(), 1e-6);
  }
  EXPECT_NEAR(deepest, 0.05, 1e-6);
  EXPECT_NEAR(shallowest, -0.35, 1e-6);
  // Two frames: both velocities are the one difference, (0, 0.1, 0) / 0.5 s.
  EXPECT_NEAR(p.vector("velocity", n - 1).y(), 0.2, 1e-6);
  EXPECT_NEAR(p.vector("velocity", 0).y(), 0.2, 1e-6);
  // The stick as one polyline of its two nodes.
  EXPECT_EQ(p.piece.at("NumberOfLines"), "1");
  EXPECT_EQ(p.arrays.at("Lines/connectivity"), (std::vector<double>{double(n - 2), double(n - 1)}));
  EXPECT_EQ(p.arrays.at("Polys/connectivity").size() % 3, 0u);  // the ball's triangles
  EXPECT_TRUE(fs::exists(out / "colliders.vtp"));
  const VtkPiece colliders(out / "colliders.vtp");
  EXPECT_EQ(colliders.points(), 4u);  // the floor's square
  EXPECT_EQ(colliders.arrays.at("object_id")[0], 2);
}

TEST_F(ExportCli, PenetrationIsLeftOutForAMeshCollider) {
  // A tetrahedron collider: shapes.json holds its triangles, not the grid that would give
  // its distance.
  const json mesh = json::array({{{"name", "tet"}, {"type", "mesh"}, {"inside", false},
                                  {"vertices", {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1}},
                                  {"triangles", {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3}}}});
  write_hand_run(dir_ / "run", 0.04, 0.3, mesh);
  ASSERT_EQ(run({"export", "run", "--format", "vtk"}).exit_code, 0);
  const VtkPiece p(dir_ / "run" / "export-vtk" / "frame_000000.vtp");
  EXPECT_EQ(p.arrays.count("penetration"), 0u);
  EXPECT_EQ(p.arrays.count("velocity"), 1u);
  EXPECT_NE(test::read_file(dir_ / "run" / "export-vtk" / "run.pvd").find("no penetration field"), std::string::npos);
}

// ---------------------------------------------------------------------------------------
// OBJ sequence
// ---------------------------------------------------------------------------------------

TEST_F(ExportCli, ObjFramesHoldEveryObjectInWorldCoordinates) {
  const Result sim = run({"simulate", kExportScene, "--out", "run", "--quiet"});
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  const Result e = run({"export", "run", "--format", "obj", "--every", "10"});
  ASSERT_EQ(e.exit_code, 0) << e.err;
  EXPECT_NE(e.out.find("export: 5 files, 5 frames, 3 objects"), std::string::npos) << e.out;
  const fs::path out = dir_ / "run" / "export-obj";
  EXPECT_EQ(files_named(out, "frame_"), (std::vector<std::string>{"frame_000000.obj", "frame_000010.obj", "frame_000020.obj",
                                                                    "frame_000030.obj", "frame_000040.obj"}));
  const Trajectory t(dir_ / "run" / "trajectory.csv");
  std::istringstream in(test::read_file(out / "frame_000030.obj"));
  std::string line, object;
  std::getline(in, line);
  EXPECT_EQ(line.rfind("# liedyn export of ", 0), 0u) << line;
  EXPECT_NE(line.find("frame 30 (4 of 5), time 0.3"), std::string::npos) << line;
  std::vector<std::string> objects;
  std::map<std::string, std::vector<Eigen::Vector3d>> vertices;
  std::size_t total = 0, max_index = 0;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string kind;
    s >> kind;
    if (kind == "o") {
      s >> object;
      objects.push_back(object);
    } else if (kind == "v") {
      Eigen::Vector3d v;
      s >> v.x() >> v.y() >> v.z();
      vertices[object].push_back(v);
      ++total;
    } else if (kind == "f") {
      for (std::size_t i; s >> i;) max_index = std::max(max_index, i);
    }
  }
  EXPECT_EQ(objects, (std::vector<std::string>{"floor", "brick", "cable"}));
  EXPECT_EQ(max_index, total);
  // The brick's vertices lie about its centre, within its half diagonal; the cable's tube
  // within its radius of the segments through its nodes.
  const Eigen::Vector3d centre = xyz(t.at(30, "brick", "body"));
  for (const Eigen::Vector3d& v : vertices["brick"]) EXPECT_LE((v - centre).norm(), std::sqrt(0.0025 + 0.0064 + 0.0144) + 1e-6);
  for (const Eigen::Vector3d& v : vertices["cable"]) {
    double nearest = 1e9;
    for (int j = 0; j < 8; ++j) {
      const Eigen::Vector3d a = xyz(t.at(30, "cable", "node", j)), b = xyz(t.at(30, "cable", "node", j + 1));
      const double s = std::clamp((v - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
      nearest = std::min(nearest, (a + s * (b - a) - v).norm());
    }
    EXPECT_NEAR(nearest, 0.02, 2e-3);
  }
}

TEST_F(ExportCli, ASecondExportReplacesTheFramesOfTheFirst) {
  const Result sim = run({"simulate", kExportScene, "--out", "run", "--quiet"});
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  ASSERT_EQ(run({"export", "run", "--format", "vtk"}).exit_code, 0);
  EXPECT_EQ(files_named(dir_ / "run" / "export-vtk", "frame_").size(), 41u);
  std::ofstream(dir_ / "run" / "export-vtk" / "frame_999999.vtp") << "not liedyn's";  // kept: not in run.json
  ASSERT_EQ(run({"export", "run", "--format", "vtk", "--every", "20"}).exit_code, 0);
  EXPECT_EQ(files_named(dir_ / "run" / "export-vtk", "frame_"),
            (std::vector<std::string>{"frame_000000.vtp", "frame_000020.vtp", "frame_000040.vtp", "frame_999999.vtp"}));
  const json manifest = json::parse(test::read_file(dir_ / "run" / "export-vtk" / "run.json"));
  EXPECT_EQ(manifest["files"].size(), 5u);  // three frames, colliders.vtp, run.pvd
  EXPECT_EQ(pvd_entries(dir_ / "run" / "export-vtk" / "run.pvd").size(), 3u);
}

TEST_F(ExportCli, ThousandsOfFramesAreWrittenOneFileAtATime) {
  // More files than the 256 an output folder tracks for removal on a signal, and than a
  // small descriptor limit: each frame's file is finished before the next is begun.
  write_hand_run(dir_ / "run", 0.04, 0.3, json::array(), 1100);
  const Result e = run({"export", "run", "--format", "obj"});
  ASSERT_EQ(e.exit_code, 0) << e.err;
  EXPECT_EQ(files_named(dir_ / "run" / "export-obj", "frame_", ".obj").size(), 1100u);
  EXPECT_EQ(files_named(dir_ / "run" / "export-obj", ".").size(), 0u);  // no staging folder left
}

// ---------------------------------------------------------------------------------------
// Untrusted and bad input
// ---------------------------------------------------------------------------------------

TEST_F(ExportCli, NamesFromTheRunNeverChooseAPathAndStayInsideTheirLine) {
  const json floor = json::array({{{"name", "../../floor\nv 1 2 3"}, {"type", "plane"}, {"point", {0, 0, 0}},
                                   {"normal", {0, 0, 1}}, {"inside", false}}});
  write_hand_run(dir_ / "run", 0.04, 0.3, floor);
  for (const std::string format : {"obj", "vtk", "gltf"}) {
    const Result e = run({"export", "run", "--format", format});
    ASSERT_EQ(e.exit_code, 0) << e.err;
  }
  EXPECT_EQ(files_named(dir_ / "run" / "export-obj", "", ".obj"), (std::vector<std::string>{"frame_000000.obj", "frame_000001.obj"}));
  const std::string obj = test::read_file(dir_ / "run" / "export-obj" / "frame_000000.obj");
  EXPECT_NE(obj.find("o ../../floor_v_1_2_3\n"), std::string::npos);
  EXPECT_EQ(obj.find("\nv 1 2 3"), std::string::npos);
  const std::string pvd = test::read_file(dir_ / "run" / "export-vtk" / "run.pvd");
  EXPECT_NE(pvd.find("collider ../../floor v 1 2 3 (colliders.vtp)"), std::string::npos) << pvd;
  EXPECT_EQ(load_glb(dir_ / "run" / "export-gltf" / "run.glb").nodes.back().name, "../../floor\nv 1 2 3");
  EXPECT_FALSE(fs::exists(dir_ / "floor"));
}

TEST_F(ExportCli, BadInputIsRefusedNamingTheFile) {
  // No run at all.
  Result r = run({"export", "nowhere", "--format", "obj"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("nowhere/shapes.json"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ / "nowhere"));
  // An unknown format: CLI11's check.
  write_hand_run(dir_ / "run", 0.04, 0.3, json::array());
  r = run({"export", "run", "--format", "stl"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("--format"), std::string::npos) << r.err;
  r = run({"export", "run", "--format", "obj", "--every", "0"});
  EXPECT_EQ(r.exit_code, 2);
  // A trajectory of another run.
  std::string trajectory = test::read_file(dir_ / "run" / "trajectory.csv");
  std::ofstream(dir_ / "run" / "trajectory.csv") << replace_all(trajectory, "stick", "staff");
  r = run({"export", "run", "--format", "gltf"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("trajectory.csv: line 3: is staff node 0 where shapes.json has stick node 0"), std::string::npos) << r.err;
  // A quaternion that is not one, a coordinate that is not finite.
  std::ofstream(dir_ / "run" / "trajectory.csv") << replace_all(trajectory, ",1,0,0,0\n", ",2,0,0,0\n");
  r = run({"export", "run", "--format", "vtk"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("trajectory.csv: frame 0, ball body 0: is not a unit quaternion (norm 2"), std::string::npos) << r.err;
  std::ofstream(dir_ / "run" / "trajectory.csv") << replace_all(trajectory, ",5,", ",inf,");
  r = run({"export", "run", "--format", "obj"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("trajectory.csv: frame 0, ball body 0: is not finite"), std::string::npos) << r.err;
  std::ofstream(dir_ / "run" / "trajectory.csv") << trajectory;
  // Shapes that are not: each refused with its field.
  const std::string shapes = test::read_file(dir_ / "run" / "shapes.json");
  for (const auto& [from, to, field] : std::vector<std::tuple<std::string, std::string, std::string>>{
           {R"("radius": 0.2)", R"("radius": -0.2)", "bodies[0].shape.radius: "},
           {R"("type": "sphere")", R"("type": "blob")", "bodies[0].shape.type: unknown shape type \"blob\""},
           {R"("radius": 0.2)", R"("radius": 0.2, "colour": 3)", "bodies[0].shape.colour: unknown key"},
           {R"("colliders": [])", R"("colliders": [{"name": "m", "type": "mesh", "vertices": [0, 0, 0], "triangles": [0, 0, 1]}])",
            "colliders[0].triangles[2]: must be an integer in [0, 0]"},
           {R"("colliders": [])", R"("colliders": [{"name": "p", "type": "plane", "point": [0, 0, 0], "normal": [0, 0, 0]}])",
            "colliders[0].normal: must be a non-zero vector"},
           {R"("colliders": [])", R"("colliders": [{"name": "t", "type": "tube", "points": [0, 0, 0], "radius": 1}])",
            "colliders[0].polyline: "}}) {
    std::string edited = shapes;
    const std::size_t at = edited.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    edited.replace(at, from.size(), to);
    std::ofstream(dir_ / "run" / "shapes.json") << edited;
    r = run({"export", "run", "--format", "gltf"});
    EXPECT_EQ(r.exit_code, 2) << edited;
    EXPECT_NE(r.err.find("shapes.json: " + field), std::string::npos) << r.err;
  }
  EXPECT_FALSE(fs::exists(dir_ / "run" / "export-gltf" / "run.glb"));
}

}  // namespace
}  // namespace liedyn::export_tests
