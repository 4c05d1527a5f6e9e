// Mesh upload and drawing: storage buffers read by the vertex shader, an offscreen multisampled
// framebuffer resolved into a single-sample one, and the colour and depth read back.
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <utility>

#include "lodkit/error.h"
#include "render/internal.h"

namespace lod {

namespace {

GLuint make_buffer(const void* data, size_t bytes) {
  // A storage binding must name a non-empty buffer: short (or absent) streams are padded with zeros.
  std::vector<uint8_t> padded;
  if (bytes < 16) {
    padded.assign(16, 0);
    if (bytes) std::memcpy(padded.data(), data, bytes);
    data = padded.data();
    bytes = padded.size();
  }
  GLuint buffer = 0;
  glCreateBuffers(1, &buffer);
  glNamedBufferStorage(buffer, GLsizeiptr(bytes), data, 0);
  return buffer;
}

void ensure_targets(RenderContext::State& s, uint32_t width, uint32_t height, uint32_t samples) {
  if (s.target_width == width && s.target_height == height && s.target_samples == samples) return;
  GLuint framebuffers[] = {s.multisample_fbo, s.resolve_fbo};
  glDeleteFramebuffers(2, framebuffers);
  GLuint renderbuffers[] = {s.multisample_color, s.multisample_depth, s.resolve_color, s.resolve_depth};
  glDeleteRenderbuffers(4, renderbuffers);
  s.multisample_fbo = s.resolve_fbo = s.multisample_color = s.multisample_depth = s.resolve_color = s.resolve_depth = 0;

  auto target = [&](GLuint& fbo, GLuint& color, GLuint& depth, uint32_t n) {
    glCreateFramebuffers(1, &fbo);
    glCreateRenderbuffers(1, &color);
    glCreateRenderbuffers(1, &depth);
    // 8-bit sRGB colour: shading is linear, the stored bytes are what a PNG viewer expects.
    glNamedRenderbufferStorageMultisample(color, GLsizei(n > 1 ? n : 0), GL_SRGB8_ALPHA8, GLsizei(width), GLsizei(height));
    glNamedRenderbufferStorageMultisample(depth, GLsizei(n > 1 ? n : 0), GL_DEPTH_COMPONENT32F, GLsizei(width),
                                          GLsizei(height));
    glNamedFramebufferRenderbuffer(fbo, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color);
    glNamedFramebufferRenderbuffer(fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth);
    const GLenum status = glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE)
      throw_internal("OpenGL: the offscreen framebuffer is incomplete (status " + std::to_string(status) + ") at " +
                     std::to_string(width) + "x" + std::to_string(height) + ", " + std::to_string(n) + " samples");
  };
  if (samples > 1) target(s.multisample_fbo, s.multisample_color, s.multisample_depth, samples);
  target(s.resolve_fbo, s.resolve_color, s.resolve_depth, 1);
  s.target_width = width;
  s.target_height = height;
  s.target_samples = samples;
}

void set_matrix(GLuint program, const char* name, const detail::Mat4& m) {
  float f[16];
  for (int k = 0; k < 16; ++k) f[k] = float(m[k]);
  glProgramUniformMatrix4fv(program, glGetUniformLocation(program, name), 1, GL_FALSE, f);
}

void set_vec3(GLuint program, const char* name, const float3& v) {
  glProgramUniform3f(program, glGetUniformLocation(program, name), v.x, v.y, v.z);
}

}  // namespace

GpuMesh::GpuMesh(RenderContext& context, const Mesh& mesh, const std::string& name) : context_(&context) {
  validate(mesh, name);
  const RenderContext::State& s = context.state();
  std::vector<float3> computed;
  const std::vector<float3>* normals = &mesh.normals;
  if (mesh.normals.empty()) {
    computed = smooth_normals(mesh);  // (summed at positions: smooth across UV seams)
    normals = &computed;
  }
  const size_t sizes[4] = {mesh.positions.size() * sizeof(float3), normals->size() * sizeof(float3),
                           mesh.colors.size() * sizeof(float4), mesh.indices.size() * sizeof(uint32_t)};
  static constexpr const char* streams[4] = {"positions", "normals", "colours", "indices"};
  for (int k = 0; k < 4; ++k)
    if (sizes[k] > s.max_storage_bytes)
      throw_bad_input(name, std::string("too large to draw: its ") + streams[k] + " take " + std::to_string(sizes[k]) +
                                " bytes, over the driver's storage-buffer limit of " +
                                std::to_string(s.max_storage_bytes) + " bytes");
  if (mesh.indices.size() > size_t(std::numeric_limits<GLsizei>::max()))
    throw_bad_input(name, "too many triangles to draw in one call");
  buffers_[0] = make_buffer(mesh.positions.data(), sizes[0]);
  buffers_[1] = make_buffer(normals->data(), sizes[1]);
  buffers_[2] = make_buffer(mesh.colors.data(), sizes[2]);
  buffers_[3] = make_buffer(mesh.indices.data(), sizes[3]);
  triangles_ = mesh.triangle_count();
  has_colors_ = !mesh.colors.empty();
  bounds_ = bounding_sphere(mesh);
}

void GpuMesh::release() {
  if (buffers_[0]) {
    try {
      context_->state();  // its context current, to free its buffers
      glDeleteBuffers(4, buffers_);
    } catch (const Error&) {
      // The context cannot be made current: its buffers go with it.
    }
  }
  for (uint32_t& b : buffers_) b = 0;
}

GpuMesh::~GpuMesh() { release(); }

GpuMesh::GpuMesh(GpuMesh&& other) noexcept
    : context_(other.context_),
      triangles_(other.triangles_), has_colors_(other.has_colors_), bounds_(other.bounds_) {
  for (int k = 0; k < 4; ++k) buffers_[k] = std::exchange(other.buffers_[k], 0u);
}

GpuMesh& GpuMesh::operator=(GpuMesh&& other) noexcept {
  if (this != &other) {
    release();
    context_ = other.context_;
    for (int k = 0; k < 4; ++k) buffers_[k] = std::exchange(other.buffers_[k], 0u);
    triangles_ = other.triangles_;
    has_colors_ = other.has_colors_;
    bounds_ = other.bounds_;
  }
  return *this;
}

Image render(RenderContext& context, const GpuMesh& mesh, const RenderCamera& camera, const RenderOptions& options) {
  RenderContext::State& s = context.state();
  if (options.width == 0 || options.height == 0) throw_usage("render: the image size must be at least 1x1");
  if (options.width > s.max_size || options.height > s.max_size)
    throw_usage("render: " + std::to_string(options.width) + "x" + std::to_string(options.height) +
                " is larger than the driver's limit of " + std::to_string(s.max_size) + " pixels a side");
  if (options.samples == 0) throw_usage("render: samples must be at least 1");
  if (!(options.wire_width > 0)) throw_usage("render: the wire width must be positive");
  if (options.heatmap && !mesh.has_colors())
    throw_bad_input("render", "the mesh has no vertex colours to show as a heat map (make one with lodkit compare A B --heatmap OUT.ply)");
  detail::check_camera(camera);
  const uint32_t samples = std::min(options.samples, s.max_samples);
  ensure_targets(s, options.width, options.height, samples);

  const GLuint program = s.program;
  const detail::Mat4 view = detail::view_matrix(camera);
  const detail::Mat4 projection = detail::projection_matrix(camera, double(options.width) / options.height);
  set_matrix(program, "view", view);
  set_matrix(program, "projection", projection);
  const bool colors = mesh.has_colors() && (options.vertex_colors || options.heatmap);
  glProgramUniform1i(program, glGetUniformLocation(program, "use_colors"), colors);
  set_vec3(program, "base_color", options.base_color);
  glProgramUniform1i(program, glGetUniformLocation(program, "flat_shading"), options.shading == Shading::flat);
  glProgramUniform1f(program, glGetUniformLocation(program, "ambient"), options.heatmap ? 0.6f : options.ambient);
  glProgramUniform1i(program, glGetUniformLocation(program, "wireframe"), options.wireframe);
  glProgramUniform1f(program, glGetUniformLocation(program, "wire_width"), options.wire_width);
  set_vec3(program, "wire_color", options.wire_color);

  const GLuint draw_fbo = samples > 1 ? s.multisample_fbo : s.resolve_fbo;
  glBindFramebuffer(GL_FRAMEBUFFER, draw_fbo);
  glViewport(0, 0, GLsizei(options.width), GLsizei(options.height));
  glEnable(GL_FRAMEBUFFER_SRGB);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_GREATER);  // reversed depth: nearer is larger
  glDisable(GL_CULL_FACE);
  glClearColor(options.background.x, options.background.y, options.background.z, 1.0f);
  glClearDepth(0.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  if (mesh.triangle_count() > 0) {
    glUseProgram(program);
    for (GLuint k = 0; k < 4; ++k) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, k, mesh.buffer(int(k)));
    glBindVertexArray(s.vertex_array);
    glDrawArrays(GL_TRIANGLES, 0, GLsizei(mesh.triangle_count() * 3));
  }
  if (samples > 1)
    glBlitNamedFramebuffer(s.multisample_fbo, s.resolve_fbo, 0, 0, GLint(options.width), GLint(options.height), 0, 0,
                           GLint(options.width), GLint(options.height), GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT,
                           GL_NEAREST);

  Image image;
  image.width = options.width;
  image.height = options.height;
  const size_t pixels = size_t(options.width) * options.height;
  std::vector<uint8_t> rgba(pixels * 4);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, s.resolve_fbo);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, GLsizei(options.width), GLsizei(options.height), GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  // GL's rows go bottom to top; images go top to bottom.
  image.rgba.resize(pixels * 4);
  const size_t row = size_t(options.width) * 4;
  for (uint32_t y = 0; y < options.height; ++y)
    std::memcpy(&image.rgba[y * row], &rgba[(options.height - 1 - y) * row], row);
  if (options.read_depth) {
    std::vector<float> depth(pixels);
    glReadPixels(0, 0, GLsizei(options.width), GLsizei(options.height), GL_DEPTH_COMPONENT, GL_FLOAT, depth.data());
    image.depth.resize(pixels);
    for (uint32_t y = 0; y < options.height; ++y)
      for (uint32_t x = 0; x < options.width; ++x) {
        const float d = depth[size_t(options.height - 1 - y) * options.width + x];
        // Cleared to 0 (the far plane, reversed); the fitted far plane leaves room behind the mesh.
        image.depth[size_t(y) * options.width + x] =
            d > 0 ? float(detail::eye_depth(camera, d)) : std::numeric_limits<float>::infinity();
      }
  }
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  const GLenum error = glGetError();
  if (error != GL_NO_ERROR) throw_internal("OpenGL error " + std::to_string(error) + " while rendering");
  return image;
}

Image render(RenderContext& context, const Mesh& mesh, const RenderCamera& camera, const RenderOptions& options) {
  const GpuMesh uploaded(context, mesh);
  return render(context, uploaded, camera, options);
}

}  // namespace lod
