// glTF 2.0 binary (problems/export.hpp): the model is built here and serialised by Debian's
// libtinygltf (its shared library: no TINYGLTF_IMPLEMENTATION, no stb), which writes the
// 12-byte header, the JSON chunk and the BIN chunk, each padded to 4 bytes.
#include <nlohmann/json.hpp>  // before tiny_gltf.h, which includes it too
#include <tiny_gltf.h>

#include <cstdint>
#include <cstring>
#include <limits>

#include "export_formats.hpp"
#include "scene.hpp"
#include "shapes.hpp"

namespace liedyn {
namespace {

// The buffer, its views and accessors: one view per accessor, each 4-byte aligned (every
// component here is 4 bytes wide).
class Buffers {
 public:
  explicit Buffers(tinygltf::Model& model) : model_(model) {
    model_.buffers.emplace_back();
  }

  // An accessor of `count` elements of `type` (TINYGLTF_TYPE_VEC3, …) over `values`;
  // with_bounds: min and max per component (required on POSITION and on sampler inputs).
  template <class T>
  int accessor(const std::vector<T>& values, int component_type, int type, int components, bool with_bounds,
               int target = 0) {
    std::vector<unsigned char>& data = model_.buffers[0].data;
    tinygltf::BufferView view;
    view.buffer = 0;
    view.byteOffset = data.size();
    view.byteLength = values.size() * sizeof(T);
    view.target = target;
    data.resize(data.size() + view.byteLength);
    std::memcpy(data.data() + view.byteOffset, values.data(), view.byteLength);
    model_.bufferViews.push_back(view);

    tinygltf::Accessor a;
    a.bufferView = static_cast<int>(model_.bufferViews.size()) - 1;
    a.byteOffset = 0;
    a.normalized = false;
    a.componentType = component_type;
    a.type = type;
    a.count = values.size() / static_cast<std::size_t>(components);
    if (with_bounds) {
      a.minValues.assign(static_cast<std::size_t>(components), std::numeric_limits<double>::infinity());
      a.maxValues.assign(static_cast<std::size_t>(components), -std::numeric_limits<double>::infinity());
      for (std::size_t i = 0; i < values.size(); ++i) {
        const std::size_t c = i % static_cast<std::size_t>(components);
        a.minValues[c] = std::min<double>(a.minValues[c], values[i]);
        a.maxValues[c] = std::max<double>(a.maxValues[c], values[i]);
      }
    }
    model_.accessors.push_back(a);
    return static_cast<int>(model_.accessors.size()) - 1;
  }

  std::size_t bytes() const { return model_.buffers[0].data.size(); }

 private:
  tinygltf::Model& model_;
};

int add_material(tinygltf::Model& model, const char* name, std::vector<double> colour, bool see_through) {
  tinygltf::Material m;
  m.name = name;
  m.pbrMetallicRoughness.baseColorFactor = std::move(colour);
  m.pbrMetallicRoughness.metallicFactor = 0.0;
  m.pbrMetallicRoughness.roughnessFactor = 0.6;
  if (see_through) {
    m.alphaMode = "BLEND";
    m.doubleSided = true;  // an "inside" collider is seen from within
  }
  model.materials.push_back(m);
  return static_cast<int>(model.materials.size()) - 1;
}

// A mesh of one triangle primitive (no normals: glTF viewers then draw flat faces); −1 for an
// empty one (an accessor holds at least one element).
int add_mesh(tinygltf::Model& model, Buffers& buffers, const std::string& name, const TriangleMesh& mesh,
             int material) {
  if (mesh.vertices.empty() || mesh.triangles.empty()) return -1;
  std::vector<float> positions;
  positions.reserve(3 * mesh.vertices.size());
  for (const Vector3& v : mesh.vertices) {
    for (int c = 0; c < 3; ++c) positions.push_back(static_cast<float>(v[c]));
  }
  std::vector<std::uint32_t> indices;
  indices.reserve(3 * mesh.triangles.size());
  for (const auto& t : mesh.triangles) {
    for (const int i : t) indices.push_back(static_cast<std::uint32_t>(i));
  }
  tinygltf::Primitive p;
  p.attributes["POSITION"] = buffers.accessor(positions, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, 3, true,
                                              TINYGLTF_TARGET_ARRAY_BUFFER);
  p.indices = buffers.accessor(indices, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, TINYGLTF_TYPE_SCALAR, 1, false,
                               TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
  p.material = material;
  p.mode = TINYGLTF_MODE_TRIANGLES;
  tinygltf::Mesh m;
  m.name = name;
  m.primitives.push_back(p);
  model.meshes.push_back(m);
  return static_cast<int>(model.meshes.size()) - 1;
}

// One node's samples over the exported frames.
struct Track {
  std::vector<float> translation, rotation, scale;  // 3, 4 (x, y, z, w: glTF's order), 3 per frame

  void add(const Vector3& x, Eigen::Quaterniond q) {
    // q and −q are one rotation, but LINEAR interpolation follows the sign: keep each
    // quaternion on the side of the previous one, so that every step turns the short way.
    if (rotation.size() >= 4) {
      const float* last = rotation.data() + rotation.size() - 4;
      if (q.x() * last[0] + q.y() * last[1] + q.z() * last[2] + q.w() * last[3] < 0.0) q.coeffs() *= -1.0;
    }
    for (int c = 0; c < 3; ++c) translation.push_back(static_cast<float>(x[c]));
    for (const double c : {q.x(), q.y(), q.z(), q.w()}) rotation.push_back(static_cast<float>(c));
  }
};

tinygltf::Node animated_node(const std::string& name, int mesh, const Track& track) {
  tinygltf::Node node;
  node.name = name;
  node.mesh = mesh;
  // The first frame's pose, for readers that do not play the animation.
  node.translation.assign(track.translation.begin(), track.translation.begin() + 3);
  node.rotation.assign(track.rotation.begin(), track.rotation.begin() + 4);
  if (!track.scale.empty()) node.scale.assign(track.scale.begin(), track.scale.begin() + 3);
  return node;
}

void animate(Buffers& buffers, tinygltf::Animation& animation, int times, int node,
             const Track& track) {
  const auto channel = [&](const std::vector<float>& values, int type, int components, const char* path) {
    tinygltf::AnimationSampler sampler;
    sampler.input = times;
    sampler.output = buffers.accessor(values, TINYGLTF_COMPONENT_TYPE_FLOAT, type, components, false);
    sampler.interpolation = "LINEAR";
    animation.samplers.push_back(sampler);
    tinygltf::AnimationChannel c;
    c.sampler = static_cast<int>(animation.samplers.size()) - 1;
    c.target_node = node;
    c.target_path = path;
    animation.channels.push_back(c);
  };
  channel(track.translation, TINYGLTF_TYPE_VEC3, 3, "translation");
  channel(track.rotation, TINYGLTF_TYPE_VEC4, 4, "rotation");
  if (!track.scale.empty()) channel(track.scale, TINYGLTF_TYPE_VEC3, 3, "scale");
}

}  // namespace

std::vector<std::string> write_gltf(const ExportJob& job, OutputFolder& folder) {
  const RecordedRun& run = job.run;
  const ExportGeometry& g = job.geometry;
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "liedyn export";
  Buffers buffers(model);
  const int body_material = add_material(model, "body", {0.33, 0.52, 0.80, 1.0}, false);
  const int rod_material = add_material(model, "rod", {0.90, 0.50, 0.20, 1.0}, false);
  const int collider_material = add_material(model, "collider", {0.60, 0.62, 0.66, 0.35}, true);

  // Sampler input: the exported times, strictly increasing as glTF requires (also once
  // rounded to float).
  std::vector<float> times;
  for (const std::size_t f : job.frames) {
    const float t = static_cast<float>(run.times[f]);
    if (!times.empty() && !(t > times.back())) {
      throw SceneError((run.dir / "trajectory.csv").string(), "frame " + std::to_string(run.frame_numbers[f]),
                       "time " + std::to_string(run.times[f]) +
                           " s does not follow the previous exported frame's in single precision "
                           "(glTF needs increasing times)");
    }
    times.push_back(t);
  }
  const int time_accessor = buffers.accessor(times, TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_SCALAR, 1, true);
  tinygltf::Animation animation;
  animation.name = "run";
  tinygltf::Scene scene;
  scene.name = run.shapes.value("title", std::string("liedyn run"));

  const auto add_node = [&](tinygltf::Node node) {
    model.nodes.push_back(std::move(node));
    scene.nodes.push_back(static_cast<int>(model.nodes.size()) - 1);
    return static_cast<int>(model.nodes.size()) - 1;
  };
  for (const ExportGeometry::Body& body : g.bodies) {
    const int mesh = add_mesh(model, buffers, body.name, body.mesh, body_material);
    Track track;
    for (const std::size_t f : job.frames) {
      const RigidPose pose = row_pose(run, f, body.row);
      track.add(pose.position, pose.rotation);
    }
    const int node = add_node(animated_node(body.name, mesh, track));
    animate(buffers, animation, time_accessor, node, track);
  }
  for (const ExportGeometry::Rod& rod : g.rods) {
    // One cylinder for all the rod's edges: unit length along z, scaled to each edge.
    const int mesh = add_mesh(model, buffers, rod.name + "/edge",
                              tessellate(CylinderShape{rod.radius, 0.5}, job.options.rod_segments), rod_material);
    for (int j = 0; j + 1 < rod.nodes; ++j) {
      Track track;
      for (const std::size_t f : job.frames) {
        const Vector3 a = node_position(run, f, rod.first_node_row + j);
        const Vector3 b = node_position(run, f, rod.first_node_row + j + 1);
        track.add(0.5 * (a + b), row_pose(run, f, rod.first_edge_row + j).rotation);
        for (const double s : {1.0, 1.0, (b - a).norm()}) track.scale.push_back(static_cast<float>(s));
      }
      const int node = add_node(animated_node(rod.name + "/edge " + std::to_string(j), mesh, track));
      animate(buffers, animation, time_accessor, node, track);
    }
  }
  for (const ExportGeometry::Obstacle& c : g.colliders) {
    tinygltf::Node node;
    node.name = c.name;
    node.mesh = add_mesh(model, buffers, c.name, c.mesh, collider_material);
    add_node(std::move(node));
  }
  model.animations.push_back(animation);
  model.scenes.push_back(scene);
  model.defaultScene = 0;

  // A GLB's lengths are 32-bit: the whole file must stay below 4 GiB (JSON ~ 200 bytes per
  // accessor besides the buffer).
  const double estimate = double(buffers.bytes()) + 400.0 * double(model.accessors.size()) + 4096.0;
  if (estimate >= double(std::numeric_limits<std::uint32_t>::max())) {
    throw SceneError((run.dir / "trajectory.csv").string(), "",
                     "is too long for one glTF binary (" + std::to_string(buffers.bytes() >> 20) +
                         " MiB of samples; at most 4 GiB): export fewer frames with --every");
  }
  const std::string name = "run.glb";
  std::ostream& out = folder.add(name);
  tinygltf::TinyGLTF writer;
  if (!writer.WriteGltfSceneToStream(&model, out, false, true)) {
    throw std::runtime_error((folder.path() / name).string() + ": tinygltf could not write the glTF binary");
  }
  folder.finish(name);
  return {name};
}

}  // namespace liedyn
