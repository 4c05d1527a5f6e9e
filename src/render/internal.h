// What the render module's files share: the context's GL objects and small matrix helpers.
#pragma once

// epoxy first: it stands in for khrplatform.h, which EGL/egl.h would otherwise bring in conflicting.
#include <epoxy/gl.h>
#include <EGL/egl.h>

#include <array>
#include <string>

#include "lodkit/render.h"

namespace lod {

struct RenderContext::State {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  EGLSurface surface = EGL_NO_SURFACE;  // a 1x1 pbuffer, only when the driver lacks surfaceless contexts
  std::string renderer, version;
  uint32_t max_samples = 1;
  uint64_t max_storage_bytes = 0;  // GL_MAX_SHADER_STORAGE_BLOCK_SIZE
  uint32_t max_size = 0;           // GL_MAX_RENDERBUFFER_SIZE

  GLuint program = 0;
  GLuint vertex_array = 0;  // core profile draws need one bound, even with no attributes
  // Offscreen targets, kept between renders of the same size and sample count.
  GLuint multisample_fbo = 0, resolve_fbo = 0;
  GLuint multisample_color = 0, multisample_depth = 0, resolve_color = 0, resolve_depth = 0;
  uint32_t target_width = 0, target_height = 0, target_samples = 0;
};

namespace detail {

using Mat4 = std::array<double, 16>;  // column-major, as GL takes it

// World to eye (right-handed, looking down -z) and eye to clip, for a camera and an image aspect.
// The projection maps depth to [0, 1] reversed (near 1, far 0; glClipControl zero-to-one), which keeps
// float depth precise over the whole range.
Mat4 view_matrix(const RenderCamera& camera);
Mat4 projection_matrix(const RenderCamera& camera, double aspect);
// Throws lod::Error (usage) for a camera no image can be made from.
void check_camera(const RenderCamera& camera);
// The reversed [0, 1] window depth back to the distance along the view axis.
double eye_depth(const RenderCamera& camera, double window_depth);

}  // namespace detail
}  // namespace lod
