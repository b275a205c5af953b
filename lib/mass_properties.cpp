#include "mass_properties.hpp"

#include <cmath>
#include <numbers>
#include <variant>

#include "model.hpp"

namespace liedyn {
namespace {

constexpr double kPi = std::numbers::pi;

struct Moments {
  double volume = 0.0;
  Vector3 second = Vector3::Zero();  // ∫x², ∫y², ∫z² about the centre, shape axes
};

Moments sphere(double r) {
  return {4.0 * kPi * r * r * r / 3.0, Vector3::Constant(4.0 * kPi * std::pow(r, 5) / 15.0)};
}

Moments capsule(double h, double r) {
  const double r2 = r * r, r4 = r2 * r2, r5 = r4 * r;
  const double cylinder = 2.0 * kPi * r2 * h;
  const double half_sphere = 2.0 * kPi * r2 * r / 3.0;
  Moments m;
  m.volume = cylinder + 2.0 * half_sphere;
  const double across = kPi * r4 * h / 2.0 + 2.0 * (2.0 * kPi * r5 / 15.0);
  const double along = 2.0 * kPi * r2 * h * h * h / 3.0 +
                       2.0 * (h * h * half_sphere + 2.0 * h * kPi * r4 / 4.0 + 2.0 * kPi * r5 / 15.0);
  m.second = Vector3(across, across, along);
  return m;
}

Moments rounded_box(const Vector3& outer, double r) {
  const Vector3 a = outer - Vector3::Constant(r);
  const double disc = kPi * r * r / 4.0, disc_u = r * r * r / 3.0, disc_u2 = kPi * std::pow(r, 4) / 16.0;
  const double octant = kPi * r * r * r / 6.0, octant_u = kPi * std::pow(r, 4) / 16.0,
               octant_u2 = kPi * std::pow(r, 5) / 30.0;
  Moments m;
  m.volume = 8.0 * a.prod() + 8.0 * r * (a.y() * a.z() + a.x() * a.z() + a.x() * a.y()) +
             4.0 * disc * 2.0 * a.sum() + 8.0 * octant;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3, k = (i + 2) % 3;
    const double ai = a[i], aj = a[j], ak = a[k];
    const double core_i2 = 2.0 * ai * ai * ai / 3.0;  // ∫x_i² over [−a_i, a_i]
    double s = core_i2 * 4.0 * aj * ak;                                     // inner box
    s += 2.0 * (std::pow(ai + r, 3) - ai * ai * ai) / 3.0 * 4.0 * aj * ak;  // the two slabs across i
    s += 2.0 * core_i2 * r * 2.0 * ak + 2.0 * core_i2 * r * 2.0 * aj;       // the slabs across j and k
    const double beyond_disc = ai * ai * disc + 2.0 * ai * disc_u + disc_u2;
    s += 4.0 * 2.0 * ak * beyond_disc + 4.0 * 2.0 * aj * beyond_disc;  // edges along k and j
    s += 4.0 * disc * core_i2;                                         // edges along i
    s += 8.0 * (ai * ai * octant + 2.0 * ai * octant_u + octant_u2);   // corners
    m.second[i] = s;
  }
  return m;
}

}  // namespace

MassProperties mass_properties(const Collider& shape, double density, const std::string& path) {
  if (!std::isfinite(density) || !(density > 0.0)) {
    throw ModelError(path + ".density", "must be a finite positive number of kg/m³");
  }
  if (shape.position.norm() != 0.0) {
    throw ModelError(path + ".contact.shape.position",
                     "must be the body's origin (its centre of mass) when the body gives a \"density\"");
  }
  Moments m;
  if (const auto* s = std::get_if<SphereShape>(&shape.shape)) {
    m = sphere(s->radius);
  } else if (const auto* c = std::get_if<CapsuleShape>(&shape.shape)) {
    m = capsule(c->half_length, c->radius);
  } else if (const auto* b = std::get_if<BoxShape>(&shape.shape)) {
    m = rounded_box(b->half_extents, b->rounding);
  } else {
    throw ModelError(path + ".contact.shape.type", "a \"density\" needs a sphere, a box or a capsule");
  }
  MassProperties out;
  out.mass = density * m.volume;
  const Matrix3 about_centre = density * (m.second.sum() * Matrix3::Identity() - Matrix3(m.second.asDiagonal()));
  out.inertia = shape.orientation * about_centre * shape.orientation.transpose();
  return out;
}

}  // namespace liedyn
