#pragma once
// The ultrasound thread (the soft-tissue scene): at the scene's frame rate it renders a B-mode
// image in the probe's plane from the case's CT through the newest deformed tet mesh and
// publishes us_frame_t on the image LCM instance, beside the X-ray frames' socket. Only built
// when the scene lists "ultrasound".
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <string>
#include <vector>

#include "anatomy/case/case.h"
#include "pcisim_lcm/us_frame_t.hpp"
#include "protocol/encoded_publisher.h"
#include "server/scene/scene.h"
#include "server/shared_state.h"
#include "ultrasound/render/bmode_renderer.h"

namespace pcisim::server {

class UltrasoundLoop {
 public:
  // rest_tet_vertices_m and tets: the tissue's coarse tet mesh at rest (physics builds it); the
  // case's CT is what the image samples. Throws std::invalid_argument when the case has no CT
  UltrasoundLoop(const Scene& scene, const anatomy::Case& anatomy, const Eigen::Matrix3Xd& rest_tet_vertices_m,
                 const std::vector<std::array<int, 4>>& tets, SharedState& state, lcm::LCM* images);
  void run();  // until state.stop

  // one frame from the newest snapshot (run() calls it at the frame rate; tests call it directly);
  // none before physics' first step
  void render_and_publish();
  const ultrasound::BModeImage& last_image() const { return *image_; }

 private:
  UltrasoundSpec spec_;
  SharedState& state_;
  lcm::LCM* images_;
  std::unique_ptr<ultrasound::BModeRenderer> renderer_;
  ultrasound::TetSnapshot mesh_;
  const ultrasound::BModeImage* image_ = nullptr;
  pcisim_lcm::us_frame_t msg_{};
  const std::string channel_;             // a std::string once: publish() takes one (17 chars: no small-string buffer)
  protocol::EncodedPublisher publisher_;  // msg_ encoded into a buffer sized once
  int64_t seq_ = 0;
};

}  // namespace pcisim::server
