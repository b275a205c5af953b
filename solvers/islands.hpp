#pragma once
// The islands of each step, built once per set of couplings and kept.
//
// A step's islands are the components of the couplings in force at it (build_components):
// springs always, a joint in its active_frames (JointSpec::active_at), a pair of bodies
// while they touch. Model::coupling_key writes which of them hold as a key: IslandCache
// builds what a consumer needs for a key (the Simulator: a step solver per island, with its
// sparsity pattern and symbolic factorisation; the adjoint: a Hessian solve per island) the
// first time that key appears, and hands back the same objects whenever it holds again. A
// run whose couplings never change builds once; one that changes builds once per distinct
// key, and allocates nothing in the steps in between (the key is compared in place).

#include <map>
#include <utility>
#include <vector>

#include "../lib/incremental_potential.hpp"

namespace liedyn {

template <class Islands>
class IslandCache {
 public:
  // The islands of `key` (Model::coupling_key): from the cache, or make() the first time the
  // key appears. The reference stays valid for the cache's lifetime.
  template <class Make>
  Islands& at(const std::vector<bool>& key, Make&& make) {
    if (current_ != nullptr && current_->first == key) return current_->second;
    auto it = cache_.find(key);
    if (it == cache_.end()) it = cache_.emplace(key, make()).first;
    current_ = &*it;
    return current_->second;
  }

  // Number of distinct keys built so far.
  std::size_t size() const { return cache_.size(); }

  // f(islands) for every set built so far.
  template <class Function>
  void for_each(Function&& f) {
    for (auto& [key, islands] : cache_) f(islands);
  }

 private:
  std::map<std::vector<bool>, Islands> cache_;
  std::pair<const std::vector<bool>, Islands>* current_ = nullptr;
};

}  // namespace liedyn
