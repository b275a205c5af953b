#include "mesh_sdf.hpp"

#include <Eigen/Geometry>  // cross
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <tuple>

namespace liedyn {
namespace {

[[noreturn]] void fail(const std::string& reason) {
  throw std::invalid_argument("GridSdf: " + reason);
}

[[noreturn]] void too_costly(const std::string& reason) { throw GridSdfTooCostly("GridSdf: " + reason); }

// Seconds per point-triangle distance of the build (closest_point and the culling around it),
// measured: 11–20 ns on one core (-O3, icospheres of 20 to 81920 triangles on 58³–128³
// nodes; fewer triangles cost more per distance). For the messages.
constexpr double kSecondsPerDistance = 15e-9;
// Sampled nodes for estimate_work: a path costs ~2–4 T distances (the lists stay near T for
// the first levels, whose blocks are larger than the mesh).
constexpr int kMinSamples = 16, kMaxSamples = 256;

std::string str(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

// The shortest text that reads back as v ("0.0008", not 0.00080000000000000004), in fixed
// notation where that stays short.
std::string shortest(double v) {
  char buffer[400];
  const bool fixed = std::abs(v) >= 1e-6 && std::abs(v) < 1e15;
  const auto result = fixed ? std::to_chars(buffer, buffer + sizeof buffer, v, std::chars_format::fixed)
                            : std::to_chars(buffer, buffer + sizeof buffer, v);
  return std::string(buffer, result.ptr);
}

// Voronoi regions of a triangle (a, b, c) = (v0, v1, v2). Local edge k runs from v_k to
// v_{k+1 mod 3}: kEdge01 = edge 0, kEdge12 = edge 1, kEdge20 = edge 2.
enum class Region { kVertex0, kVertex1, kVertex2, kEdge01, kEdge12, kEdge20, kFace };

struct Triangle {
  Vector3 a, b, c;
  Vector3 normal;                      // unit outward normal n_t
  std::array<Vector3, 3> edge_normal;  // n_t + n_t' for local edge k (unnormalised)
  std::array<int, 3> vertex;           // indices into the vertex pseudonormals
};

// Closest point of triangle (a, b, c) to p and its Voronoi region: Ericson, Real-Time
// Collision Detection §5.1.5 (ClosestPtPointTriangle), unchanged but for the region output.
// Denominators are > 0 for a non-degenerate triangle: d1 − d3 = ‖ab‖², d2 − d6 = ‖ac‖²,
// (d4 − d3) + (d5 − d6) = ‖bc‖², va + vb + vc = ‖ab × ac‖².
Vector3 closest_point(const Vector3& p, const Triangle& t, Region& region) {
  const Vector3 ab = t.b - t.a, ac = t.c - t.a, ap = p - t.a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) {
    region = Region::kVertex0;
    return t.a;
  }
  const Vector3 bp = p - t.b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) {
    region = Region::kVertex1;
    return t.b;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    region = Region::kEdge01;
    return t.a + (d1 / (d1 - d3)) * ab;
  }
  const Vector3 cp = p - t.c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) {
    region = Region::kVertex2;
    return t.c;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    region = Region::kEdge20;
    return t.a + (d2 / (d2 - d6)) * ac;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    region = Region::kEdge12;
    return t.b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (t.c - t.b);
  }
  region = Region::kFace;
  const double denom = 1.0 / (va + vb + vc);
  return t.a + ab * (vb * denom) + ac * (vc * denom);
}

// One directed triangle edge, keyed by its sorted vertex pair.
struct HalfEdge {
  int lo, hi;    // vertex indices, lo < hi
  int triangle;  // owning triangle
  int local;     // local edge k: from vertex k to vertex k + 1 (mod 3)
  bool forward;  // the triangle runs lo → hi
};

// Checks the mesh (constructor comment) and returns the triangles with their pseudonormals
// (header): face normals, edge normals n_t + n_t', angle-weighted vertex normals, all
// oriented so that the solid is the bounded side.
std::vector<Triangle> prepare(const TriangleMesh& mesh, std::vector<Vector3>& vertex_normal) {
  const std::vector<Vector3>& v = mesh.vertices;
  if (v.empty()) fail("the mesh has no vertices");
  if (mesh.triangles.empty()) fail("the mesh has no triangles");
  if (mesh.triangles.size() > static_cast<std::size_t>(std::numeric_limits<int>::max() / 3)) {
    fail("the mesh has too many triangles (" + std::to_string(mesh.triangles.size()) + ")");
  }
  const int nv = static_cast<int>(std::min<std::size_t>(v.size(), std::numeric_limits<int>::max()));
  for (int i = 0; i < nv; ++i) {
    if (!v[static_cast<std::size_t>(i)].allFinite()) {
      std::ostringstream s;
      s << "vertex " << i << " is not finite (" << v[static_cast<std::size_t>(i)].transpose()
        << ")";
      fail(s.str());
    }
  }
  const int nt = static_cast<int>(mesh.triangles.size());
  std::vector<Triangle> tris(static_cast<std::size_t>(nt));
  for (int t = 0; t < nt; ++t) {
    const std::array<int, 3>& f = mesh.triangles[static_cast<std::size_t>(t)];
    const std::string name = "triangle " + std::to_string(t) + " (vertices " +
                             std::to_string(f[0]) + ", " + std::to_string(f[1]) + ", " +
                             std::to_string(f[2]) + ")";
    for (int k = 0; k < 3; ++k) {
      if (f[static_cast<std::size_t>(k)] < 0 || f[static_cast<std::size_t>(k)] >= nv) {
        fail(name + " has vertex index " + std::to_string(f[static_cast<std::size_t>(k)]) +
             ", outside [0, " + std::to_string(nv) + ") (the mesh has " + std::to_string(nv) +
             " vertices)");
      }
    }
    if (f[0] == f[1] || f[1] == f[2] || f[2] == f[0]) {
      fail(name + " is degenerate: it repeats a vertex (zero area)");
    }
    Triangle& tri = tris[static_cast<std::size_t>(t)];
    tri.a = v[static_cast<std::size_t>(f[0])];
    tri.b = v[static_cast<std::size_t>(f[1])];
    tri.c = v[static_cast<std::size_t>(f[2])];
    tri.vertex = f;
    const Vector3 n = (tri.b - tri.a).cross(tri.c - tri.a);
    const double longest2 = std::max({(tri.b - tri.a).squaredNorm(), (tri.c - tri.b).squaredNorm(),
                                      (tri.a - tri.c).squaredNorm()});
    if (!(n.norm() > 1e-12 * longest2)) {
      fail(name + " is degenerate: zero area (|(b - a) x (c - a)| = " + str(n.norm()) +
           " <= 1e-12 x longest edge^2 = " + str(1e-12 * longest2) + ")");
    }
    tri.normal = n.normalized();
  }

  // Closedness and orientation: every undirected edge in exactly two triangles, run in
  // opposite directions. Sorted by vertex pair, so the first offending edge is reported.
  std::vector<HalfEdge> edges;
  edges.reserve(3 * static_cast<std::size_t>(nt));
  for (int t = 0; t < nt; ++t) {
    const std::array<int, 3>& f = mesh.triangles[static_cast<std::size_t>(t)];
    for (int k = 0; k < 3; ++k) {
      const int from = f[static_cast<std::size_t>(k)];
      const int to = f[static_cast<std::size_t>((k + 1) % 3)];
      edges.push_back({std::min(from, to), std::max(from, to), t, k, from < to});
    }
  }
  std::sort(edges.begin(), edges.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return std::tie(x.lo, x.hi, x.triangle, x.local) < std::tie(y.lo, y.hi, y.triangle, y.local);
  });
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i + 1;
    while (j < edges.size() && edges[j].lo == edges[i].lo && edges[j].hi == edges[i].hi) ++j;
    const std::string edge =
        "edge (" + std::to_string(edges[i].lo) + ", " + std::to_string(edges[i].hi) + ")";
    if (j - i == 1) {
      fail("the mesh is not closed: " + edge + " of triangle " + std::to_string(edges[i].triangle) +
           " belongs to no other triangle (every edge must be shared by exactly two "
           "triangles)");
    }
    if (j - i > 2) {
      std::string list;
      for (std::size_t m = i; m < j; ++m) {
        list += (m > i ? ", " : "") + std::to_string(edges[m].triangle);
      }
      fail("the mesh is not closed: " + edge + " is shared by " + std::to_string(j - i) +
           " triangles (" + list + "); every edge must be shared by exactly two triangles");
    }
    const HalfEdge& e0 = edges[i];
    const HalfEdge& e1 = edges[i + 1];
    if (e0.forward == e1.forward) {
      fail("the mesh is not consistently oriented: triangles " + std::to_string(e0.triangle) +
           " and " + std::to_string(e1.triangle) + " run along " + edge +
           " in the same direction (one of them is flipped)");
    }
    const Vector3 sum = tris[static_cast<std::size_t>(e0.triangle)].normal +
                        tris[static_cast<std::size_t>(e1.triangle)].normal;
    tris[static_cast<std::size_t>(e0.triangle)].edge_normal[static_cast<std::size_t>(e0.local)] =
        sum;
    tris[static_cast<std::size_t>(e1.triangle)].edge_normal[static_cast<std::size_t>(e1.local)] =
        sum;
    i = j;
  }

  // Signed volume ⅙ Σ a·(b × c) (divergence theorem), relative to the origin of the mesh's
  // bounding box (round-off independent of where the mesh sits).
  Vector3 lo = tris[0].a, hi = tris[0].a;
  for (const Triangle& t : tris) {
    for (const Vector3* x : {&t.a, &t.b, &t.c}) {
      lo = lo.cwiseMin(*x);
      hi = hi.cwiseMax(*x);
    }
  }
  double volume = 0.0;
  for (const Triangle& t : tris) volume += (t.a - lo).dot((t.b - lo).cross(t.c - lo)) / 6.0;
  const double size = (hi - lo).maxCoeff();
  if (!(std::abs(volume) > 1e-12 * size * size * size)) {
    fail("the mesh encloses no volume (signed volume " + str(volume) + ")");
  }
  const double orient = volume > 0.0 ? 1.0 : -1.0;  // −1: normals point inward, flip them

  vertex_normal.assign(v.size(), Vector3::Zero());
  for (Triangle& t : tris) {
    t.normal *= orient;
    for (Vector3& e : t.edge_normal) e *= orient;
    const std::array<const Vector3*, 3> x = {&t.a, &t.b, &t.c};
    for (std::size_t k = 0; k < 3; ++k) {
      const Vector3 e1 = *x[(k + 1) % 3] - *x[k];
      const Vector3 e2 = *x[(k + 2) % 3] - *x[k];
      const double angle = std::atan2(e1.cross(e2).norm(), e1.dot(e2));  // α_t ∈ (0, π)
      vertex_normal[static_cast<std::size_t>(t.vertex[k])] += angle * t.normal;
    }
  }
  return tris;
}

// Exact signed distances at all grid nodes by the recursive block culling of the header.
class NodeSolver {
 public:
  NodeSolver(const std::vector<Triangle>& tris, const std::vector<Vector3>& vertex_normal,
             const Vector3& origin, double h, const Eigen::Vector3i& dims,
             std::vector<double>& values)
      : tris_(tris),
        vertex_normal_(vertex_normal),
        origin_(origin),
        h_(h),
        dims_(dims),
        values_(values) {
    const Vector3 top = origin + h * (dims - Eigen::Vector3i::Ones()).cast<double>();
    // Distances carry round-off of a few ulps of the coordinates: culling keeps a margin far
    // above it (it only costs a few extra candidates).
    margin_ =
        1e-10 * (origin.cwiseAbs().cwiseMax(top.cwiseAbs()).maxCoeff() + (top - origin).norm());
    // Recursion depth ≤ log2(2³¹) + 2: the outer vector never reallocates during the recursion.
    lists_.resize(40);
    lists_[0].resize(tris.size());
    for (std::size_t t = 0; t < tris.size(); ++t) lists_[0][t] = static_cast<int>(t);
  }

  // Fills every node, counting point-triangle distances in work(); throws TooCostly (with
  // the count so far) once work() would pass max_work.
  void run(double max_work) {
    max_work_ = max_work;
    const std::array<int, 3> lo = {0, 0, 0};
    const std::array<int, 3> hi = {dims_.x(), dims_.y(), dims_.z()};
    block(lo, hi, 0);
  }
  double work() const { return work_; }

  // Thrown by run() when the build passes its work cap.
  struct TooCostly {
    double work;  // distances evaluated so far
  };

  // An unbiased estimate of the distances run() evaluates (header, "Work budget"), from the
  // root-to-leaf paths of `samples` nodes, each uniform over the grid. run() evaluates W = Σ_blocks c(B) + Σ_leaves n(L) k(L),
  // c(B) = the candidates block B starts from, n = its nodes, k(L) = the candidates a leaf
  // keeps for each of its nodes. Spreading c(B) over the nodes of B,
  //   W = Σ_x q(x),   q(x) = Σ_{B ∋ x} c(B)/n(B) + k(leaf(x)),
  // so N · mean q over uniform nodes estimates W without bias. One path costs what its
  // blocks cost in run(): T at the root, then the shrinking lists, ~2T in all. Uses the
  // candidate lists, so not during run().
  double estimate_work(int samples) {
    const std::uint64_t nodes = static_cast<std::uint64_t>(dims_.x()) *
                                static_cast<std::uint64_t>(dims_.y()) *
                                static_cast<std::uint64_t>(dims_.z());
    // Nodes of a randomly shifted R3 sequence (Roberts' generalised golden ratio; a fixed
    // shift, so the same grid always gets the same estimate): each one uniform over the grid
    // (the estimate stays unbiased), together spread more evenly than independent draws. In
    // a sphere the cost of a node falls with its distance from the centre: independent draws
    // missed by ±30% with 64 nodes where these stay within ~10%.
    constexpr double kPhi3 = 1.2207440846057596;  // x³ = x + 1
    const Vector3 alpha(1.0 / kPhi3, 1.0 / (kPhi3 * kPhi3), 1.0 / (kPhi3 * kPhi3 * kPhi3));
    const Vector3 shift(0.5772156649015329, 0.6180339887498949, 0.4142135623730951);
    double sum = 0.0;
    for (int s = 0; s < samples; ++s) {
      std::array<int, 3> x{};
      for (int a = 0; a < 3; ++a) {
        const double u = shift(a) + static_cast<double>(s) * alpha(a);
        const int i = static_cast<int>((u - std::floor(u)) * dims_(a));
        x[static_cast<std::size_t>(a)] = std::clamp(i, 0, dims_(a) - 1);
      }
      std::array<int, 3> lo = {0, 0, 0};
      std::array<int, 3> hi = {dims_.x(), dims_.y(), dims_.z()};
      for (std::size_t depth = 0;; ++depth) {
        const double n = static_cast<double>(hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
        sum += static_cast<double>(lists_[depth].size()) / n;
        const std::vector<int>& kept = cull(lo, hi, depth);
        if (leaf(lo, hi)) {
          sum += static_cast<double>(kept.size());
          break;
        }
        for (std::size_t a = 0; a < 3; ++a) {  // the child holding x (halves as in block)
          const int mid = lo[a] + (hi[a] - lo[a]) / 2;
          if (hi[a] - lo[a] <= 1) continue;
          if (x[a] < mid) {
            hi[a] = mid;
          } else {
            lo[a] = mid;
          }
        }
      }
    }
    return static_cast<double>(nodes) * sum / samples;
  }

 private:
  static bool leaf(const std::array<int, 3>& lo, const std::array<int, 3>& hi) {
    return hi[0] - lo[0] <= 2 && hi[1] - lo[1] <= 2 && hi[2] - lo[2] <= 2;
  }
  Vector3 node(int i, int j, int k) const {
    return origin_ +
           h_ * Vector3(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k));
  }

  // The candidates of block [lo, hi) into lists_[depth + 1], from its parent's lists_[depth]:
  // those with d_t(centre) ≤ min + 2δ (header, "Build cost"). Returns them.
  const std::vector<int>& cull(const std::array<int, 3>& lo, const std::array<int, 3>& hi,
                               std::size_t depth) {
    const Vector3 first = node(lo[0], lo[1], lo[2]);
    const Vector3 last = node(hi[0] - 1, hi[1] - 1, hi[2] - 1);
    const Vector3 centre = 0.5 * (first + last);
    const double delta = 0.5 * (last - first).norm();

    // d_t(centre) for every candidate; keep d_t ≤ min + 2δ (header, "Build cost").
    const std::vector<int>& parent = lists_[depth];
    std::vector<int>& kept = lists_[depth + 1];
    distance_.resize(parent.size());
    double best = std::numeric_limits<double>::infinity();
    Region region = Region::kFace;
    for (std::size_t m = 0; m < parent.size(); ++m) {
      const Triangle& t = tris_[static_cast<std::size_t>(parent[m])];
      distance_[m] = (centre - closest_point(centre, t, region)).norm();
      best = std::min(best, distance_[m]);
    }
    const double bound = best + 2.0 * delta + margin_;
    kept.clear();
    for (std::size_t m = 0; m < parent.size(); ++m) {
      if (distance_[m] <= bound) kept.push_back(parent[m]);  // keeps increasing index order
    }
    return kept;
  }

  // Nodes [lo, hi) (per axis); candidate triangles lists_[depth].
  void block(const std::array<int, 3>& lo, const std::array<int, 3>& hi, std::size_t depth) {
    work_ += static_cast<double>(lists_[depth].size());
    if (work_ > max_work_) throw TooCostly{work_};
    const std::vector<int>& kept = cull(lo, hi, depth);
    if (leaf(lo, hi)) {
      const double nodes = static_cast<double>(hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
      work_ += nodes * static_cast<double>(kept.size());
      for (int k = lo[2]; k < hi[2]; ++k) {
        for (int j = lo[1]; j < hi[1]; ++j) {
          for (int i = lo[0]; i < hi[0]; ++i) solve_node(i, j, k, kept);
        }
      }
      return;
    }
    // Children: halves along every axis longer than one node.
    std::array<std::array<int, 3>, 2> clo{}, chi{};
    std::array<int, 3> parts{};
    for (std::size_t a = 0; a < 3; ++a) {
      const int n = hi[a] - lo[a];
      clo[0][a] = lo[a];
      chi[1][a] = hi[a];
      if (n > 1) {
        chi[0][a] = clo[1][a] = lo[a] + n / 2;
        parts[a] = 2;
      } else {
        chi[0][a] = hi[a];
        parts[a] = 1;
      }
    }
    for (int cz = 0; cz < parts[2]; ++cz) {
      for (int cy = 0; cy < parts[1]; ++cy) {
        for (int cx = 0; cx < parts[0]; ++cx) {
          const std::array<int, 3> l = {clo[cx][0], clo[cy][1], clo[cz][2]};
          const std::array<int, 3> u = {chi[cx][0], chi[cy][1], chi[cz][2]};
          block(l, u, depth + 1);
        }
      }
    }
  }

  // φ at one node: nearest candidate (first on ties), signed by its feature's pseudonormal.
  void solve_node(int i, int j, int k, const std::vector<int>& candidates) {
    const Vector3 x = node(i, j, k);
    double best = std::numeric_limits<double>::infinity();
    Vector3 best_point = Vector3::Zero();
    Region best_region = Region::kFace;
    int best_t = -1;
    for (const int t : candidates) {
      Region region = Region::kFace;
      const Vector3 c = closest_point(x, tris_[static_cast<std::size_t>(t)], region);
      const double d2 = (x - c).squaredNorm();
      if (d2 < best) {  // strict: ties keep the lowest triangle index
        best = d2;
        best_point = c;
        best_region = region;
        best_t = t;
      }
    }
    const Triangle& t = tris_[static_cast<std::size_t>(best_t)];
    const Vector3* normal = &t.normal;
    switch (best_region) {
      case Region::kVertex0:
        normal = &vertex_normal_[static_cast<std::size_t>(t.vertex[0])];
        break;
      case Region::kVertex1:
        normal = &vertex_normal_[static_cast<std::size_t>(t.vertex[1])];
        break;
      case Region::kVertex2:
        normal = &vertex_normal_[static_cast<std::size_t>(t.vertex[2])];
        break;
      case Region::kEdge01:
        normal = &t.edge_normal[0];
        break;
      case Region::kEdge12:
        normal = &t.edge_normal[1];
        break;
      case Region::kEdge20:
        normal = &t.edge_normal[2];
        break;
      case Region::kFace:
        break;
    }
    const double d = (x - best_point).norm();
    const double side = (x - best_point).dot(*normal);
    values_[static_cast<std::size_t>(i) +
            static_cast<std::size_t>(dims_.x()) *
                (static_cast<std::size_t>(j) +
                 static_cast<std::size_t>(dims_.y()) * static_cast<std::size_t>(k))] =
        side < 0.0 ? -d : d;
  }

  const std::vector<Triangle>& tris_;
  const std::vector<Vector3>& vertex_normal_;
  Vector3 origin_;
  double h_;
  Eigen::Vector3i dims_;
  std::vector<double>& values_;
  double margin_ = 0.0;
  double work_ = 0.0;      // point-triangle distances evaluated by run() so far
  double max_work_ = 0.0;  // run() stops beyond it
  std::vector<std::vector<int>> lists_;  // candidates per recursion depth
  std::vector<double> distance_;         // scratch: d_t(centre) of the current block
};

}  // namespace

GridSdf::GridSdf(const TriangleMesh& mesh, double cell_size, double padding, long max_cells,
                 double max_build_work) {
  if (!std::isfinite(cell_size) || !(cell_size > 0.0)) {
    fail("cell_size must be finite and > 0, got " + str(cell_size));
  }
  if (!std::isfinite(padding) || !(padding >= 0.0)) {
    fail("padding must be finite and >= 0, got " + str(padding));
  }
  if (max_cells < 1) fail("max_cells must be >= 1, got " + std::to_string(max_cells));
  if (!(max_build_work >= 1.0)) fail("max_build_work must be >= 1, got " + str(max_build_work));
  std::vector<Vector3> vertex_normal;
  const std::vector<Triangle> tris = prepare(mesh, vertex_normal);

  // Bounding box of the vertices used by triangles, grown by the padding (header, "Grid").
  Vector3 lo = tris[0].a, hi = tris[0].a;
  for (const Triangle& t : tris) {
    for (const Vector3* x : {&t.a, &t.b, &t.c}) {
      lo = lo.cwiseMin(*x);
      hi = hi.cwiseMax(*x);
    }
  }
  const Vector3 extent = (hi - lo) + Vector3::Constant(2.0 * padding);
  Vector3 cells;
  constexpr double kMaxNodes = static_cast<double>(std::numeric_limits<int>::max()) - 1.0;
  static const char* const kAxis[] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    cells(a) = std::max(1.0, std::ceil(extent(a) / cell_size - 1e-9));
    if (!(cells(a) + 1.0 <= kMaxNodes)) {
      too_costly("the grid needs " + str(cells(a)) + " cells along " + kAxis[a] + " (padded extent " +
           str(extent(a)) + " m / cell_size " + str(cell_size) +
           "), more than 2^31 - 2 nodes along an axis");
    }
  }
  const double total = cells.prod();
  if (!(total <= static_cast<double>(max_cells))) {
    std::ostringstream s;
    s << "the grid needs " << cells.x() << " x " << cells.y() << " x " << cells.z() << " = "
      << str(total) << " cells, more than max_cells = " << max_cells
      << " (increase cell_size = " << str(cell_size) << " or max_cells)";
    too_costly(s.str());
  }
  h_ = cell_size;
  dims_ = (cells + Vector3::Ones()).cast<int>();
  origin_ = lo - Vector3::Constant(padding) - 0.5 * (cell_size * cells - extent);
  max_corner_ = origin_ + h_ * (dims_ - Eigen::Vector3i::Ones()).cast<double>();
  values_.assign(static_cast<std::size_t>(dims_.x()) * static_cast<std::size_t>(dims_.y()) *
                     static_cast<std::size_t>(dims_.z()),
                 0.0);

  // The work budget (header, "Build cost"): estimated first where it could matter.
  NodeSolver solver(tris, vertex_normal, origin_, h_, dims_, values_);
  const double nodes = static_cast<double>(values_.size());
  const double triangles = static_cast<double>(tris.size());
  // "max_build_work = …: increase cell_size …", for a build of `work` distances.
  const auto budget_and_advice = [&](double work) {
    std::ostringstream s;
    s << std::setprecision(3) << "max_build_work = " << max_build_work << " (~"
      << std::setprecision(2) << max_build_work * kSecondsPerDistance << " s; this build ~"
      << work * kSecondsPerDistance << " s, at ~" << kSecondsPerDistance * 1e9
      << " ns per distance on one core): increase cell_size = " << shortest(cell_size)
      << " to about " << std::setprecision(3) << cell_size * std::sqrt(work / max_build_work)
      << " or more (the work falls as 1/cell_size^2 to 1/cell_size^3), or use a mesh with "
         "fewer triangles";
    return s.str();
  };
  if (3.0 * nodes * triangles > max_build_work) {  // run() evaluates at most 3 N T distances
    const int samples = std::clamp(
        static_cast<int>(0.1 * max_build_work / (4.0 * triangles)), kMinSamples, kMaxSamples);
    const double estimate = solver.estimate_work(samples);
    estimated_work_ = estimate;
    if (estimate > max_build_work) {
      std::ostringstream s;
      s << "building the grid of " << dims_.x() << " x " << dims_.y() << " x " << dims_.z()
        << " nodes for " << tris.size() << " triangles needs about " << std::setprecision(3)
        << estimate << " point-triangle distances (estimated from " << samples
        << " sampled nodes), more than " << budget_and_advice(estimate);
      too_costly(s.str());
    }
  }
  try {
    solver.run(2.0 * max_build_work);
  } catch (const NodeSolver::TooCostly& stop) {
    std::ostringstream s;
    s << "building the grid of " << dims_.x() << " x " << dims_.y() << " x " << dims_.z()
      << " nodes for " << tris.size() << " triangles was stopped after " << std::setprecision(3)
      << stop.work << " point-triangle distances (estimated beforehand: " << estimated_work_
      << "), twice " << budget_and_advice(stop.work);
    too_costly(s.str());
  }
  build_work_ = solver.work();
}

Vector3 GridSdf::node_position(int i, int j, int k) const {
  if (i < 0 || j < 0 || k < 0 || i >= dims_.x() || j >= dims_.y() || k >= dims_.z()) {
    throw std::out_of_range("GridSdf::node_position: node (" + std::to_string(i) + ", " +
                            std::to_string(j) + ", " + std::to_string(k) + ") outside the grid");
  }
  // Same expression as NodeSolver::node: the value at this position is node_value(i, j, k).
  return origin_ +
         h_ * Vector3(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k));
}

double GridSdf::node_value(int i, int j, int k) const {
  if (i < 0 || j < 0 || k < 0 || i >= dims_.x() || j >= dims_.y() || k >= dims_.z()) {
    throw std::out_of_range("GridSdf::node_value: node (" + std::to_string(i) + ", " +
                            std::to_string(j) + ", " + std::to_string(k) + ") outside the grid");
  }
  return values_[index(i, j, k)];
}

void GridSdf::interpolate(const Vector3& q, bool with_hessian, SdfValue& out) const {
  // Cell c with c < u ≤ c + 1 (ties to the lower cell), clamped to the grid; t = u − c. A u
  // within kFaceUlps ulps of an integer is on that face: node_position(i, ·, ·) gives
  // u = i(1 ± ε), which must still count as the face.
  constexpr double kFaceUlps = 8.0;
  std::array<int, 3> c{};
  Vector3 t;
  for (int a = 0; a < 3; ++a) {
    const double u = (q(a) - origin_(a)) / h_;  // in [0, n − 1] up to round-off
    const double nearest = std::round(u);
    const bool on_face = std::abs(u - nearest) <=
                         kFaceUlps * std::numeric_limits<double>::epsilon() * std::max(1.0, u);
    const int ca = static_cast<int>(on_face ? nearest : std::ceil(u)) - 1;
    c[static_cast<std::size_t>(a)] = std::clamp(ca, 0, dims_(a) - 2);
    t(a) = u - c[static_cast<std::size_t>(a)];
  }
  const auto v = [&](int a, int b, int d) { return values_[index(c[0] + a, c[1] + b, c[2] + d)]; };
  // dx_bc = v_1bc − v_0bc, e_bc = v_0bc + t_x dx_bc (the x-interpolated edge values).
  const double dx00 = v(1, 0, 0) - v(0, 0, 0), dx10 = v(1, 1, 0) - v(0, 1, 0);
  const double dx01 = v(1, 0, 1) - v(0, 0, 1), dx11 = v(1, 1, 1) - v(0, 1, 1);
  const double e00 = v(0, 0, 0) + t.x() * dx00, e10 = v(0, 1, 0) + t.x() * dx10;
  const double e01 = v(0, 0, 1) + t.x() * dx01, e11 = v(0, 1, 1) + t.x() * dx11;
  const double wy0 = 1.0 - t.y(), wy1 = t.y(), wz0 = 1.0 - t.z(), wz1 = t.z();
  // φ = Σ_bc e_bc w_b(t_y) w_c(t_z).
  out.distance = wz0 * (wy0 * e00 + wy1 * e10) + wz1 * (wy0 * e01 + wy1 * e11);
  // ∂φ/∂t_x = Σ_bc dx_bc w_b w_c, ∂φ/∂t_y = Σ_c (e_1c − e_0c) w_c, ∂φ/∂t_z = Σ_b (e_b1 − e_b0) w_b.
  const double inv_h = 1.0 / h_;
  out.gradient =
      inv_h * Vector3(wz0 * (wy0 * dx00 + wy1 * dx10) + wz1 * (wy0 * dx01 + wy1 * dx11),
                      wz0 * (e10 - e00) + wz1 * (e11 - e01), wy0 * (e01 - e00) + wy1 * (e11 - e10));
  if (!with_hessian) return;
  // Mixed partials (the diagonal is 0: the interpolant is linear along each axis):
  //   ∂²φ/∂t_x∂t_y = Σ_c (dx_1c − dx_0c) w_c,  ∂²φ/∂t_x∂t_z = Σ_b (dx_b1 − dx_b0) w_b,
  //   ∂²φ/∂t_y∂t_z = e_11 − e_10 − e_01 + e_00.
  const double inv_h2 = inv_h * inv_h;
  const double hxy = inv_h2 * (wz0 * (dx10 - dx00) + wz1 * (dx11 - dx01));
  const double hxz = inv_h2 * (wy0 * (dx01 - dx00) + wy1 * (dx11 - dx10));
  const double hyz = inv_h2 * (e11 - e10 - e01 + e00);
  out.hessian << 0.0, hxy, hxz,  //
      hxy, 0.0, hyz,             //
      hxz, hyz, 0.0;
}

SdfValue GridSdf::evaluate(const Vector3& p, bool with_hessian) const {
  SdfValue out;
  if (!p.allFinite()) {  // header: a non-finite coordinate gives φ = NaN
    out.distance = std::numeric_limits<double>::quiet_NaN();
    out.gradient.setConstant(std::numeric_limits<double>::quiet_NaN());
    return out;
  }
  const Vector3 q = p.cwiseMax(origin_).cwiseMin(max_corner_);  // nearest point of the box
  interpolate(q, with_hessian, out);
  const Vector3 w = p - q;  // non-zero exactly on the clamped axes A
  const double m = w.cwiseAbs().maxCoeff();
  if (m == 0.0) return out;  // inside the box
  const Vector3 ws = w / m;  // scaled: ‖w‖ without overflow or underflow
  const double ns = ws.norm();
  const double d = m * ns;
  if (d <= kCoreDistance) return out;  // at the box to round-off: inside
  const Vector3 u = ws / ns;
  // φ(p) = φ(q) + d, ∇φ = P_F ∇φ(q) + u, ∇²φ = P_F ∇²φ(q) P_F + (P_A − u uᵀ)/d (header).
  const Vector3 free_axes = (w.array() == 0.0).cast<double>();
  out.distance += d;
  out.gradient = free_axes.cwiseProduct(out.gradient) + u;
  if (with_hessian) {
    const Matrix3 projected = free_axes.asDiagonal() * out.hessian * free_axes.asDiagonal();
    const Vector3 active = Vector3::Ones() - free_axes;
    out.hessian = projected + (Matrix3(active.asDiagonal()) - u * u.transpose()) / d;
  }
  return out;
}

}  // namespace liedyn
