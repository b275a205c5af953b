#pragma once
// Warnings about a scene that loads but is probably not what its author meant: the run goes
// on, the driver prints each on stderr ("liedyn: warning: …").
//  - colliders that nothing can touch (no body or rod has a contact block);
//  - a contact sample or rod node whose centre starts inside a collider (deeper than its
//    radius): the penalty then pushes it out with a force of k·depth, which can launch it;
//  - two bodies whose contact samples start overlapping: bodies touch colliders, not each
//    other, so they will pass through one another.

#include <string>
#include <vector>

#include "scene.hpp"

namespace liedyn {

std::vector<std::string> scene_warnings(const Scene& scene);

}  // namespace liedyn
