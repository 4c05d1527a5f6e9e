// The headless OpenGL 4.5 core context (EGL without a window system) and the shaders every render
// uses. Each way it can fail says which piece is missing, so a machine without a driver gets a
// message to act on rather than a crash.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <string>

#include "lodkit/error.h"
#include "render/internal.h"  // EGL/egl.h, which eglext.h needs first

#include <EGL/eglext.h>

namespace lod {

namespace {

std::string egl_error_name(EGLint code) {
  switch (code) {
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    default: {
      char text[16];
      std::snprintf(text, sizeof text, "0x%04x", unsigned(code));
      return text;
    }
  }
}

bool has_extension(const char* list, const char* name) {
  if (!list) return false;
  const size_t length = std::strlen(name);
  for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += length)
    if ((p == list || p[-1] == ' ') && (p[length] == ' ' || p[length] == '\0')) return true;
  return false;
}

constexpr const char* driver_hint =
    "install Mesa's EGL and software driver (Debian: libegl1 libegl-mesa0 libgl1-mesa-dri) or a GPU driver";

// The display: surfaceless Mesa first (no GPU needed), else the first EGL device (how NVIDIA's
// driver renders headless). glvnd's libEGL reports no client extensions when it finds no vendor
// library at all, which is the "no driver" case.
EGLDisplay open_display() {
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (!client || !*client)
    throw_bad_input("OpenGL", std::string("no EGL driver: libEGL found no vendor library (glvnd's egl_vendor.d, "
                                          "__EGL_VENDOR_LIBRARY_FILENAMES); ") + driver_hint);
  if (has_extension(client, "EGL_MESA_platform_surfaceless")) {
    EGLDisplay display = eglGetPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (display != EGL_NO_DISPLAY) return display;
  }
  if (has_extension(client, "EGL_EXT_platform_device") && has_extension(client, "EGL_EXT_device_enumeration")) {
    auto query_devices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
    EGLDeviceEXT device = nullptr;
    EGLint count = 0;
    if (query_devices && query_devices(1, &device, &count) && count > 0) {
      EGLDisplay display = eglGetPlatformDisplay(EGL_PLATFORM_DEVICE_EXT, device, nullptr);
      if (display != EGL_NO_DISPLAY) return display;
    }
  }
  throw_bad_input("OpenGL", std::string("no headless EGL platform: the EGL driver offers neither "
                                        "EGL_MESA_platform_surfaceless nor a device (EGL_EXT_platform_device); ") +
                                driver_hint);
}

// Throws with the driver's log when a shader or program failed to build (and deletes it).
template <typename GetIv, typename GetLog, typename Delete>
void check_built(GLuint object, GLenum status, GetIv get_iv, GetLog get_log, Delete destroy, const char* what) {
  GLint ok = 0;
  get_iv(object, status, &ok);
  if (ok) return;
  char log[2048] = {};
  get_log(object, sizeof log, nullptr, log);
  destroy(object);
  throw_internal(std::string("OpenGL: shader ") + what + " failed: " + log);
}

GLuint compile(GLenum stage, const char* source) {
  const GLuint shader = glCreateShader(stage);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  check_built(shader, GL_COMPILE_STATUS, glGetShaderiv, glGetShaderInfoLog, glDeleteShader, "compilation");
  return shader;
}

// Vertex pulling: no vertex attributes; each of the 3 * T vertex invocations reads its index and
// the vertex streams from storage buffers. Unindexed drawing gives every corner its own
// barycentric coordinate for the wireframe while the mesh stays indexed in memory.
constexpr const char* vertex_shader = R"(#version 450 core
layout(std430, binding = 0) readonly buffer Positions { float positions[]; };
layout(std430, binding = 1) readonly buffer Normals { float normals[]; };
layout(std430, binding = 2) readonly buffer Colors { vec4 colors[]; };
layout(std430, binding = 3) readonly buffer Indices { uint indices[]; };
uniform mat4 view;             // object to eye
uniform mat4 projection;       // eye to clip
uniform bool use_colors;
uniform vec3 base_color;
out vec3 eye_position;
out vec3 eye_normal;
out vec3 albedo;
out vec3 barycentric;
void main() {
  uint i = indices[gl_VertexID];
  vec4 p = vec4(positions[3u * i], positions[3u * i + 1u], positions[3u * i + 2u], 1.0);
  vec3 n = vec3(normals[3u * i], normals[3u * i + 1u], normals[3u * i + 2u]);
  vec4 eye = view * p;
  eye_position = eye.xyz;
  eye_normal = mat3(view) * n;
  albedo = use_colors ? colors[i].rgb : base_color;
  int corner = gl_VertexID % 3;
  barycentric = vec3(corner == 0, corner == 1, corner == 2);
  gl_Position = projection * eye;
}
)";

// Lambert with a headlight: a directional light along the view axis (eye-space +z), so a face turned
// to the camera gets exactly its albedo. Output is linear; the sRGB framebuffer encodes it.
constexpr const char* fragment_shader = R"(#version 450 core
in vec3 eye_position;
in vec3 eye_normal;
in vec3 albedo;
in vec3 barycentric;
uniform bool flat_shading;
uniform float ambient;
uniform bool wireframe;
uniform float wire_width;
uniform vec3 wire_color;
out vec4 color;
void main() {
  float lambert;
  if (flat_shading) {
    // The triangle's plane from screen-space derivatives; it always faces the eye.
    vec3 n = cross(dFdx(eye_position), dFdy(eye_position));
    float len = length(n);
    lambert = len > 0.0 ? abs(n.z) / len : 1.0;
  } else {
    vec3 n = eye_normal;
    float len = length(n);
    n = len > 0.0 ? n / len : vec3(0.0, 0.0, 1.0);
    if (!gl_FrontFacing) n = -n;  // light both sides: open meshes show their inside
    lambert = max(n.z, 0.0);
  }
  vec3 c = albedo * min(ambient + (1.0 - ambient) * lambert, 1.0);
  if (wireframe) {
    // Distance to the nearest edge in pixels, from the barycentrics' screen-space rates.
    vec3 rate = max(fwidth(barycentric), vec3(1e-12));
    vec3 pixels = barycentric / rate;
    float edge = min(min(pixels.x, pixels.y), pixels.z);
    float line = 1.0 - smoothstep(wire_width * 0.5, wire_width * 0.5 + 1.0, edge);
    c = mix(c, wire_color, line);
  }
  color = vec4(c, 1.0);
}
)";

GLuint link_program() {
  const GLuint vs = compile(GL_VERTEX_SHADER, vertex_shader);
  const GLuint fs = compile(GL_FRAGMENT_SHADER, fragment_shader);
  const GLuint program = glCreateProgram();
  glAttachShader(program, vs);
  glAttachShader(program, fs);
  glLinkProgram(program);
  glDeleteShader(vs);
  glDeleteShader(fs);
  check_built(program, GL_LINK_STATUS, glGetProgramiv, glGetProgramInfoLog, glDeleteProgram, "linking");
  return program;
}

// Undoes whatever part of the context was made when the constructor throws half-way.
void destroy(RenderContext::State& s) {
  if (s.display == EGL_NO_DISPLAY) return;
  if (s.context != EGL_NO_CONTEXT && eglMakeCurrent(s.display, s.surface, s.surface, s.context)) {
    GLuint framebuffers[] = {s.multisample_fbo, s.resolve_fbo};
    glDeleteFramebuffers(2, framebuffers);
    GLuint renderbuffers[] = {s.multisample_color, s.multisample_depth, s.resolve_color, s.resolve_depth};
    glDeleteRenderbuffers(4, renderbuffers);
    if (s.vertex_array) glDeleteVertexArrays(1, &s.vertex_array);
    if (s.program) glDeleteProgram(s.program);
    eglMakeCurrent(s.display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  }
  if (s.context != EGL_NO_CONTEXT) eglDestroyContext(s.display, s.context);
  if (s.surface != EGL_NO_SURFACE) eglDestroySurface(s.display, s.surface);
  // No eglTerminate: the display is shared by every context in the process (Mesa frees it at exit).
  eglReleaseThread();
  s.display = EGL_NO_DISPLAY;
}

void create(RenderContext::State& s) {
  s.display = open_display();
  EGLint major = 0, minor = 0;
  if (!eglInitialize(s.display, &major, &minor)) {
    const EGLint code = eglGetError();
    s.display = EGL_NO_DISPLAY;  // nothing to release
    throw_bad_input("OpenGL", "the EGL driver could not initialise a headless display (" + egl_error_name(code) +
                                  "): is Mesa's software rasteriser there? " + driver_hint);
  }
  if (!eglBindAPI(EGL_OPENGL_API))
    throw_bad_input("OpenGL", std::string("the EGL driver has no desktop OpenGL (eglBindAPI(EGL_OPENGL_API) failed); ") +
                                  driver_hint);
  const char* extensions = eglQueryString(s.display, EGL_EXTENSIONS);
  const bool surfaceless = has_extension(extensions, "EGL_KHR_surfaceless_context");
  const bool no_config = has_extension(extensions, "EGL_KHR_no_config_context") ||
                         has_extension(extensions, "EGL_MESA_configless_context");
  EGLConfig config = nullptr;
  if (!surfaceless || !no_config) {
    // Older drivers: a config and a 1x1 pbuffer to be current on; the drawing still goes to our FBOs.
    const EGLint attributes[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
    EGLint count = 0;
    if (!eglChooseConfig(s.display, attributes, &config, 1, &count) || count < 1)
      throw_bad_input("OpenGL", "the EGL driver has no OpenGL pbuffer config and no surfaceless contexts; " +
                                    std::string(driver_hint));
  }
  const EGLint context_attributes[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                                       EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
  s.context = eglCreateContext(s.display, config, EGL_NO_CONTEXT, context_attributes);
  if (s.context == EGL_NO_CONTEXT)
    throw_bad_input("OpenGL", "the EGL driver offers no OpenGL 4.5 core context (" + egl_error_name(eglGetError()) +
                                  "); lodkit render needs OpenGL 4.5 (Mesa llvmpipe has it)");
  if (!surfaceless) {
    const EGLint pbuffer[] = {EGL_WIDTH, 1, EGL_HEIGHT, 1, EGL_NONE};
    s.surface = eglCreatePbufferSurface(s.display, config, pbuffer);
    if (s.surface == EGL_NO_SURFACE)
      throw_bad_input("OpenGL", "the EGL driver could not make a pbuffer (" + egl_error_name(eglGetError()) + ")");
  }
  if (!eglMakeCurrent(s.display, s.surface, s.surface, s.context))
    throw_bad_input("OpenGL", "could not make the OpenGL context current (" + egl_error_name(eglGetError()) + ")");
  if (epoxy_gl_version() < 45)
    throw_bad_input("OpenGL", "the driver's OpenGL is " + std::to_string(epoxy_gl_version() / 10) + "." +
                                  std::to_string(epoxy_gl_version() % 10) + "; lodkit render needs 4.5 core");

  s.renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  s.version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  GLint value = 0;
  glGetIntegerv(GL_MAX_SAMPLES, &value);
  s.max_samples = uint32_t(std::max(value, 1));
  glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &value);
  s.max_size = uint32_t(std::max(value, 1));
  GLint64 storage = 0;
  glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &storage);
  s.max_storage_bytes = uint64_t(std::max<GLint64>(storage, 0));

  s.program = link_program();
  glCreateVertexArrays(1, &s.vertex_array);
  // Reversed depth in [0, 1] with a float buffer: precise at every distance.
  glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
}

}  // namespace

RenderContext::RenderContext() : state_(std::make_unique<State>()) {
  try {
    create(*state_);
  } catch (...) {
    destroy(*state_);
    throw;
  }
}

RenderContext::~RenderContext() { destroy(*state_); }

RenderContext::State& RenderContext::state() {
  State& s = *state_;
  // Another context may have been made current on this thread since.
  if (eglGetCurrentContext() != s.context && !eglMakeCurrent(s.display, s.surface, s.surface, s.context))
    throw_internal("OpenGL: could not make the context current (EGL error " + std::to_string(eglGetError()) + ")");
  return s;
}

const std::string& RenderContext::renderer() const { return state_->renderer; }
const std::string& RenderContext::version() const { return state_->version; }
uint32_t RenderContext::max_samples() const { return state_->max_samples; }

}  // namespace lod
