#include "scene_checks.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <sstream>

namespace liedyn {
namespace {

std::string collider_label(const Model& model, std::size_t c) {
  return "colliders[" + std::to_string(c) + "] (\"" + model.colliders[c].name + "\")";
}

// The first collider that a sample of `material` touches and that `p` starts inside by more
// than its radius (its centre inside the solid): a message, or empty.
std::string deepest_start(const Model& model, const Vector3& p, const ContactMaterial& material,
                          const std::string& what) {
  const double radius = material.radius;
  for (std::size_t c = 0; c < model.colliders.size(); ++c) {
    if (!material.touches(model.colliders[c].name)) continue;
    const double phi = model.colliders[c].evaluate(p, false).distance;
    if (phi < 0.0) {
      std::ostringstream os;
      os << what << " starts " << -phi + radius << " m inside " << collider_label(model, c)
         << ", deeper than its radius " << radius
         << " m: the penalty will push it out hard (move it outside)";
      return os.str();
    }
  }
  return {};
}

// A sample of one body of a modelled pair whose centre starts inside the other's shape: a
// message, or empty.
std::string inside_other(const Model& model, int a, int b) {
  for (const auto& [sampled, solid] : {std::pair{a, b}, std::pair{b, a}}) {
    const RigidBody& s = model.bodies[sampled];
    const RigidBody& o = model.bodies[solid];
    if (!s.contact.enabled() || o.shape == nullptr) continue;
    for (std::size_t i = 0; i < s.contact_points.size(); ++i) {
      const Vector3 p = s.position + s.orientation * s.contact_points[i];
      const double phi = o.shape->evaluate(o.orientation.transpose() * (p - o.position), false).distance;
      if (phi < 0.0) {
        std::ostringstream os;
        os << "contact sample " << i << " of \"" << s.name << "\" starts " << -phi + s.contact.radius
           << " m inside the shape of \"" << o.name << "\", deeper than its radius " << s.contact.radius
           << " m: the penalty will push them apart hard (move them apart)";
        return os.str();
      }
    }
  }
  return {};
}

}  // namespace

std::vector<std::string> scene_warnings(const Scene& scene) {
  const Model& model = scene.model;
  std::vector<std::string> warnings;
  bool anything_touches = false;
  std::vector<Eigen::AlignedBox3d> boxes(model.bodies.size());  // of the samples' spheres
  for (std::size_t b = 0; b < model.bodies.size(); ++b) {
    const RigidBody& body = model.bodies[b];
    if (!body.contact.enabled() || body.contact_points.empty()) continue;
    anything_touches = true;
    const std::string label = "bodies[" + std::to_string(b) + "] (\"" + body.name + "\")";
    bool warned = false;
    for (std::size_t i = 0; i < body.contact_points.size(); ++i) {
      const Vector3 p = body.position + body.orientation * body.contact_points[i];
      boxes[b].extend(p - Vector3::Constant(body.contact.radius));
      boxes[b].extend(p + Vector3::Constant(body.contact.radius));
      if (warned) continue;
      const std::string w = deepest_start(model, p, body.contact,
                                          label + ": contact sample " + std::to_string(i));
      if (!w.empty()) {
        warnings.push_back(w);
        warned = true;  // one per body is enough to act on
      }
    }
  }
  for (std::size_t r = 0; r < model.rods.size(); ++r) {
    const RodSpec& rod = model.rods[r];
    if (!rod.contact.enabled()) continue;
    anything_touches = true;
    for (int i = 0; i < rod.node_count(); ++i) {
      if (std::find(rod.fixed_nodes.begin(), rod.fixed_nodes.end(), i) != rod.fixed_nodes.end()) {
        continue;  // clamped nodes have no contact
      }
      const std::string w =
          deepest_start(model, rod.nodes[static_cast<std::size_t>(i)], rod.contact,
                        "rods[" + std::to_string(r) + "] (\"" + rod.name + "\"): node " +
                            std::to_string(i));
      if (!w.empty()) {
        warnings.push_back(w);
        break;
      }
    }
  }
  if (!model.colliders.empty() && !anything_touches) {
    warnings.push_back(std::to_string(model.colliders.size()) +
                       " collider(s) touch nothing: no body or rod has a contact block (give "
                       "bodies \"contact\" with samples, or rods \"contact\")");
  }
  // Pairs whose contact is modelled (a shape on one, samples on the other) touch; the others
  // pass through one another if their samples start overlapping (unless told to ignore
  // each other).
  const std::vector<std::pair<int, int>> touching = model.body_pairs();
  for (std::size_t a = 0; a < boxes.size(); ++a) {
    for (std::size_t b = a + 1; b < boxes.size(); ++b) {
      const std::string pair = "bodies[" + std::to_string(a) + "] (\"" + model.bodies[a].name +
                               "\") and bodies[" + std::to_string(b) + "] (\"" + model.bodies[b].name + "\")";
      if (std::find(touching.begin(), touching.end(), std::pair{int(a), int(b)}) != touching.end()) {
        const std::string w = inside_other(model, int(a), int(b));
        if (!w.empty()) warnings.push_back(pair + ": " + w);
      } else if (!boxes[a].isEmpty() && !boxes[b].isEmpty() && boxes[a].intersects(boxes[b]) &&
                 model.bodies[a].contact.touches(model.bodies[b].name) &&
                 model.bodies[b].contact.touches(model.bodies[a].name)) {  // not told to ignore
        warnings.push_back(pair +
                           " start with overlapping contact samples (their bounding boxes "
                           "intersect) but neither has a \"shape\" to touch: they will "
                           "pass through one another");
      }
    }
  }
  return warnings;
}

}  // namespace liedyn
