#pragma once
// 3D Slicer markups files (.mrk.json): a vessel branch's centerline as an open curve, an organ's
// fiducial beads as a point list, LPS mm.
// The fields follow Slicer's markups schema v1.0.3 ("coordinateSystem": "LPS",
// "coordinateUnits": "mm"); docs/anatomy.md says how this was checked.
#include <Eigen/Core>
#include <span>
#include <string>

#include "anatomy/vessel/vessel_tree.h"

namespace pcisim::anatomy {

// one curve, its control points the branch's centerline points; throws std::runtime_error
void write_markups_curve(const VesselBranch& branch, const std::string& path);

// one point list ("Fiducial"), a control point per bead centre labelled <name>-1, -2, ...;
// throws std::runtime_error
void write_markups_fiducials(const std::string& name, std::span<const Eigen::Vector3d> points_m,
                             const std::string& path);

// a branch name made safe as a file name: every character but [A-Za-z0-9_-] becomes '_' (so no
// '/', '.' or '..' reaches a path), at most 100 characters, "branch" for an empty name
std::string markups_file_stem(const std::string& branch_name);

}  // namespace pcisim::anatomy
