#include "analysis.hpp"

#include <Eigen/SVD>
#include <iomanip>
#include <numbers>
#include <sstream>

#include "../manifolds/rotation_vector.hpp"

namespace liedyn {

std::string exp_jacobian_singular_values_csv(int samples) {
  std::ostringstream os;
  os << std::setprecision(12) << "angle,sigma1,sigma2,sigma3\n";
  const Eigen::Vector3d axis = Eigen::Vector3d(1.0, 2.0, 3.0).normalized();
  for (int k = 0; k < samples; ++k) {
    const double angle = 2.0 * std::numbers::pi * k / (samples - 1);
    const Eigen::JacobiSVD<Eigen::Matrix<double, 9, 3>> svd(rotvec::exp_jacobian(angle * axis));
    const Eigen::Vector3d s = svd.singularValues();  // sorted decreasingly
    os << angle << "," << s[0] << "," << s[1] << "," << s[2] << "\n";
  }
  return os.str();
}

}  // namespace liedyn
