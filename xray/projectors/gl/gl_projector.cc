#include "xray/projectors/gl/gl_projector.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>
#include <GL/osmesa.h>

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "xray/projectors/views.h"

namespace pcisim::xray {
namespace {

// one full-screen triangle pair; each fragment is one detector pixel
const char* kVertexShader = R"glsl(#version 330 core
const vec2 corners[6] = vec2[6](vec2(-1, -1), vec2(1, -1), vec2(1, 1), vec2(-1, -1), vec2(1, 1), vec2(-1, 1));
void main() { gl_Position = vec4(corners[gl_VertexID], 0.0, 1.0); }
)glsl";

// the same arithmetic as ray::trilinear_ray (skip_empty off): source to pixel centre in padded
// voxel coordinates, clipped to [0, n-1], midpoint samples every step voxels; the texture's
// linear filter does the trilinear read (texel centres at padded integers)
const char* kFragmentShader = R"glsl(#version 330 core
uniform sampler3D mu;
uniform vec3 padded;          // padded dims
uniform mat4 to_voxel;        // physical mm -> padded voxel coordinates
uniform vec3 src, center, u, v;
uniform float pixel_mm, step_voxels;
uniform vec2 size;            // detector width, height
uniform int max_samples;
out float integral;
void main() {
  vec2 cr = floor(gl_FragCoord.xy);  // (column, row); row 0 is the first row read back
  vec3 pix = center + (cr.x - 0.5 * (size.x - 1.0)) * pixel_mm * u + (cr.y - 0.5 * (size.y - 1.0)) * pixel_mm * v;
  float len_mm = length(pix - src);
  vec3 x0 = (to_voxel * vec4(src, 1.0)).xyz;
  vec3 dx = (to_voxel * vec4(pix, 1.0)).xyz - x0;
  float len_vox = length(dx);
  integral = 0.0;
  if (!(len_vox > 0.0)) return;
  vec3 box = padded - 1.0;
  float t0 = 0.0, t1 = 1.0;
  for (int a = 0; a < 3; ++a) {
    if (dx[a] == 0.0) {
      if (x0[a] < 0.0 || x0[a] > box[a]) return;
      continue;
    }
    float ta = (0.0 - x0[a]) / dx[a], tb = (box[a] - x0[a]) / dx[a];
    t0 = max(t0, min(ta, tb));
    t1 = min(t1, max(ta, tb));
  }
  if (!(t0 < t1)) return;
  float dt = step_voxels / len_vox;
  int k_end = min(int(ceil((t1 - t0) / dt - 0.5)), max_samples);
  float acc = 0.0;
  for (int k = 0; k < k_end; ++k) {
    vec3 x = x0 + (t0 + (float(k) + 0.5) * dt) * dx;
    acc += texture(mu, (x + 0.5) / padded).r;
  }
  integral = acc * dt * len_mm;
}
)glsl";

GLuint compile(GLenum type, const char* source) {
  const GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &source, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[2048];
    glGetShaderInfoLog(s, sizeof log, nullptr, log);
    throw std::runtime_error(fmt::format("GL projector: shader does not compile: {}", log));
  }
  return s;
}

}  // namespace

struct GlProjector::Impl {
  OSMesaContext context = nullptr;
  std::vector<unsigned char> dummy = std::vector<unsigned char>(4);  // OSMesa wants a colour buffer
  GLuint program = 0, texture = 0, vao = 0, fbo = 0, target = 0;
  int fbo_width = 0, fbo_height = 0;
  std::array<int, 3> padded{};
  ray::GridView grid;
  float step_voxels = 1.0f;

  void make_current() {
    if (!OSMesaMakeCurrent(context, dummy.data(), GL_UNSIGNED_BYTE, 1, 1))
      throw std::runtime_error("GL projector: cannot make the OSMesa context current");
  }
  GLint at(const char* name) const { return glGetUniformLocation(program, name); }
};

GlProjector::GlProjector(const AttenuationVolume& volume, double step_voxels) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  const int attributes[] = {OSMESA_FORMAT,
                            OSMESA_RGBA,
                            OSMESA_PROFILE,
                            OSMESA_CORE_PROFILE,
                            OSMESA_CONTEXT_MAJOR_VERSION,
                            3,
                            OSMESA_CONTEXT_MINOR_VERSION,
                            3,
                            0};
  m.context = OSMesaCreateContextAttribs(attributes, nullptr);
  if (!m.context) throw std::runtime_error("GL projector: OSMesa cannot make an OpenGL 3.3 core context");
  m.make_current();
  m.step_voxels = static_cast<float>(step_voxels);
  m.grid = grid_view(volume);
  m.padded = volume.padded_dims();

  // the padded attenuation as a single-channel float 3D texture, linear filtering
  glGenTextures(1, &m.texture);
  glBindTexture(GL_TEXTURE_3D, m.texture);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTexImage3D(GL_TEXTURE_3D, 0, GL_R32F, m.padded[0], m.padded[1], m.padded[2], 0, GL_RED, GL_FLOAT,
               volume.padded_mu());
  for (GLenum p : {GL_TEXTURE_MIN_FILTER, GL_TEXTURE_MAG_FILTER}) glTexParameteri(GL_TEXTURE_3D, p, GL_LINEAR);
  for (GLenum p : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T, GL_TEXTURE_WRAP_R})
    glTexParameteri(GL_TEXTURE_3D, p, GL_CLAMP_TO_EDGE);
  if (glGetError() != GL_NO_ERROR) throw std::runtime_error("GL projector: cannot upload the volume as a 3D texture");

  const GLuint vs = compile(GL_VERTEX_SHADER, kVertexShader), fs = compile(GL_FRAGMENT_SHADER, kFragmentShader);
  m.program = glCreateProgram();
  glAttachShader(m.program, vs);
  glAttachShader(m.program, fs);
  glLinkProgram(m.program);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint linked = 0;
  glGetProgramiv(m.program, GL_LINK_STATUS, &linked);
  if (!linked) throw std::runtime_error("GL projector: the shader program does not link");
  glGenVertexArrays(1, &m.vao);
  glGenFramebuffers(1, &m.fbo);
}

GlProjector::~GlProjector() {
  if (!impl_->context) return;
  impl_->make_current();
  glDeleteFramebuffers(1, &impl_->fbo);
  if (impl_->target) glDeleteTextures(1, &impl_->target);
  glDeleteTextures(1, &impl_->texture);
  glDeleteVertexArrays(1, &impl_->vao);
  glDeleteProgram(impl_->program);
  OSMesaDestroyContext(impl_->context);
}

void GlProjector::project(const DetectorGeometry& g, Image* image) {
  Impl& m = *impl_;
  m.make_current();
  // a float render target of the detector's size, made again only when the size changes
  if (g.width != m.fbo_width || g.height != m.fbo_height) {
    if (m.target) glDeleteTextures(1, &m.target);
    glGenTextures(1, &m.target);
    glBindTexture(GL_TEXTURE_2D, m.target);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_R32F, g.width, g.height, 0, GL_RED, GL_FLOAT, nullptr);
    glBindFramebuffer(GL_FRAMEBUFFER, m.fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, m.target, 0);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw std::runtime_error("GL projector: the float render target is not supported");
    m.fbo_width = g.width;
    m.fbo_height = g.height;
  }
  glBindFramebuffer(GL_FRAMEBUFFER, m.fbo);
  glViewport(0, 0, g.width, g.height);
  glUseProgram(m.program);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_3D, m.texture);
  glUniform1i(m.at("mu"), 0);
  glUniform3f(m.at("padded"), float(m.padded[0]), float(m.padded[1]), float(m.padded[2]));
  // column-major 4x4 of the affine in grid.m (rows of 4)
  float to_voxel[16] = {};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) to_voxel[c * 4 + r] = m.grid.m[4 * r + c];
  to_voxel[15] = 1.0f;
  glUniformMatrix4fv(m.at("to_voxel"), 1, GL_FALSE, to_voxel);
  const ray::DetectorView d = detector_view(g);
  glUniform3fv(m.at("src"), 1, d.src);
  glUniform3fv(m.at("center"), 1, d.center);
  glUniform3fv(m.at("u"), 1, d.u);
  glUniform3fv(m.at("v"), 1, d.v);
  glUniform1f(m.at("pixel_mm"), d.pixel_mm);
  glUniform1f(m.at("step_voxels"), m.step_voxels);
  glUniform2f(m.at("size"), float(g.width), float(g.height));
  const float diagonal =
      std::sqrt(float(m.padded[0]) * m.padded[0] + float(m.padded[1]) * m.padded[1] + float(m.padded[2]) * m.padded[2]);
  glUniform1i(m.at("max_samples"), static_cast<int>(diagonal / m.step_voxels) + 2);
  glBindVertexArray(m.vao);
  glDrawArrays(GL_TRIANGLES, 0, 6);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, g.width, g.height, GL_RED, GL_FLOAT, image->pixels.data());
  if (const GLenum e = glGetError(); e != GL_NO_ERROR)
    throw std::runtime_error(fmt::format("GL projector: GL error {:#x} while rendering", e));
}

bool gl_projector_available(std::string* why) {
  const int attributes[] = {OSMESA_FORMAT,
                            OSMESA_RGBA,
                            OSMESA_PROFILE,
                            OSMESA_CORE_PROFILE,
                            OSMESA_CONTEXT_MAJOR_VERSION,
                            3,
                            OSMESA_CONTEXT_MINOR_VERSION,
                            3,
                            0};
  OSMesaContext c = OSMesaCreateContextAttribs(attributes, nullptr);
  if (!c) {
    if (why) *why = "OSMesa cannot make an OpenGL 3.3 core context";
    return false;
  }
  OSMesaDestroyContext(c);
  return true;
}

}  // namespace pcisim::xray
