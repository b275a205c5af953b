#pragma once
// The islands of each step, built once per set of couplings and kept.
//
// A step's islands are the components of the couplings in force at it (build_components):
// springs always, a joint in its active_frames (JointSpec::active_at). Which joints hold is
// the whole of what can change between steps, so the set of active joints identifies the
// islands: IslandCache builds what a consumer needs for a set (the Simulator: a step solver
// per island, with its sparsity pattern and symbolic factorisation; the adjoint: a Hessian
// solve per island) the first time that set appears, and hands back the same objects
// whenever it holds again. A run whose couplings never change builds once; one that changes
// builds once per distinct set, and allocates nothing in the steps in between (the key is
// compared in place).

#include <map>
#include <utility>
#include <vector>

#include "../lib/incremental_potential.hpp"

namespace liedyn {

template <class Islands>
class IslandCache {
 public:
  // The islands of step `frame`: from the cache, or make(build_components(model, frame))
  // the first time its set of active joints appears. The reference stays valid for the
  // cache's lifetime.
  template <class Make>
  Islands& at(const Model& model, int frame, Make&& make) {
    key_.resize(model.joints.size());  // allocates the first time only
    for (std::size_t j = 0; j < key_.size(); ++j) key_[j] = model.joints[j].active_at(frame);
    if (current_ != nullptr && current_->first == key_) return current_->second;
    auto it = cache_.find(key_);
    if (it == cache_.end()) it = cache_.emplace(key_, make(build_components(model, frame))).first;
    current_ = &*it;
    return current_->second;
  }

  // Number of distinct sets built so far.
  std::size_t size() const { return cache_.size(); }

  // f(islands) for every set built so far.
  template <class Function>
  void for_each(Function&& f) {
    for (auto& [key, islands] : cache_) f(islands);
  }

 private:
  std::map<std::vector<bool>, Islands> cache_;
  std::vector<bool> key_;
  std::pair<const std::vector<bool>, Islands>* current_ = nullptr;
};

}  // namespace liedyn
