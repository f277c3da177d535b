#pragma once
// A cardiac motion sequence: per-frame displacement fields over one cycle on a regular grid
// (the heart paper's image-derived ventricle motion, section 4). Frame f holds phase f / frames;
// space is trilinear (clamped to the grid's box), time is periodic Catmull-Rom. File format:
// docs/heart.md. Queries allocate nothing.
#include <Eigen/Core>
#include <string>
#include <string_view>
#include <vector>

namespace pcisim::anatomy {

struct MotionGrid {
  Eigen::Vector3d origin_m = Eigen::Vector3d::Zero();   // node (0, 0, 0), patient LPS
  Eigen::Vector3d spacing_m = Eigen::Vector3d::Ones();  // > 0
  Eigen::Vector3i dims = Eigen::Vector3i::Ones();       // nodes per axis, >= 2 each
  long node_count() const { return long(dims.x()) * dims.y() * dims.z(); }
};

class HeartMotion {
 public:
  // data: frames * node_count * 3 floats (x fastest over nodes, then y, z; xyz per node).
  // Throws std::invalid_argument naming the bad field.
  HeartMotion(const MotionGrid& grid, int frames, double cycle_s, std::vector<float> data_m);

  // where the tissue that rests at rest_m has moved at phase (any real; taken modulo 1)
  Eigen::Vector3d displacement_m(const Eigen::Vector3d& rest_m, double phase) const;
  // the time interpolation alone: displacement_m = sum_k weight[k] * frame_displacement_m(frame[k])
  struct FrameWeights {
    int frame[4];
    double weight[4];
  };
  FrameWeights frame_weights(double phase) const;  // phase finite
  // one frame's field at a point (trilinear, clamped to the grid's box)
  Eigen::Vector3d frame_displacement_m(int frame, const Eigen::Vector3d& rest_m) const;
  // the stored sample at one node of one frame
  Eigen::Vector3d node_displacement_m(int frame, int i, int j, int k) const;

  int frames() const { return frames_; }
  double cycle_s() const { return cycle_s_; }
  const MotionGrid& grid() const { return grid_; }

  // the file format (docs/heart.md); name is what errors call the source
  static HeartMotion parse(std::string_view bytes, const std::string& name);
  static HeartMotion read(const std::string& path);
  std::string serialize() const;
  void write(const std::string& path) const;

 private:
  MotionGrid grid_;
  int frames_;
  double cycle_s_;
  std::vector<float> data_m_;
};

}  // namespace pcisim::anatomy
