#pragma once
// Target shapes for the "rods spell letters" problem (paper Fig. 1): straight rods whose
// initial node velocities are optimised so that, after 100 frames, each rod lies along one
// letter of "SIGGRAPH".
//
// A rod cannot lift the pen, so each letter is ONE connected polyline: a single-stroke font
// of the capitals A–Z. Letters whose usual strokes are disconnected (H, K, T, X, …) retrace
// part of themselves, as little as the letter's graph allows: a stroke drawn once per edge
// exists only when at most two junctions have an odd number of edges (Euler), and every other
// pair of odd junctions costs one retraced path between them.
//
// Coordinates: the em box of height 1, in the x–y plane (z = 0): baseline y = 0, cap height
// y = 1, the letter within 0 ≤ x ≤ 1 (most are 0.6–0.9 wide, "I" is the line x = 0). Curves
// (ellipse arcs) are sampled every 7.5° (12 segments per quarter turn) and straight strokes
// are cut into segments of at most 0.25, so that resampling to ~40 or more points follows
// the shape instead of cutting corners.

#include <Eigen/Core>
#include <vector>

namespace liedyn {

// The polyline of a capital letter A–Z (lower case is mapped to upper case) in the em box
// above; consecutive points are distinct (a retraced stroke repeats points, never in a row).
// Throws std::invalid_argument naming the character for anything else.
std::vector<Eigen::Vector3d> letter_polyline(char letter);

// Arc length Σ_i ‖p_{i+1} − p_i‖ of a polyline (0 for fewer than two points).
double polyline_length(const std::vector<Eigen::Vector3d>& polyline);

// `count` ≥ 2 points equally spaced by arc length along the polyline: point k lies at arc
// length s_k = k L / (count − 1), L = polyline_length, so the first and last points are the
// polyline's own. Retraced parts count with their length. Each point is interpolated linearly
// on the segment containing s_k, so it lies on the polyline. Throws std::invalid_argument for
// count < 2, fewer than 2 points, a non-finite point, or zero length.
std::vector<Eigen::Vector3d> resample_polyline(const std::vector<Eigen::Vector3d>& polyline,
                                               int count);

// The target shape of a rod with `count` nodes: letter_polyline(letter) scaled to `height`
// metres (> 0, finite: the em box becomes height × height), its lower-left corner (the em
// box's origin) moved to `origin`, resampled to `count` points. Throws std::invalid_argument
// for a bad letter, height, origin or count.
std::vector<Eigen::Vector3d> letter_target(char letter, double height,
                                           const Eigen::Vector3d& origin, int count);

}  // namespace liedyn
