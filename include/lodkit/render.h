// lodkit: headless OpenGL pictures of meshes, LOD chains and heat maps.
//
//   lod::RenderContext gl;                                   // EGL, OpenGL 4.5 core, no window
//   lod::RenderCamera camera = lod::fit_camera(lod::bounding_sphere(mesh), lod::view_direction("iso"), 4.0 / 3.0);
//   lod::Image image = lod::render(gl, mesh, camera, {.width = 1024, .height = 768});
//   lod::write_png(image, "bunny.png");
//
// The context is made through EGL without a window system (EGL_MESA_platform_surfaceless, else
// EGL_EXT_platform_device), so the same code runs on Mesa's llvmpipe (no GPU) and on a real GPU.
// Drawing goes to an offscreen multisampled framebuffer that is resolved and read back: RGBA8 colour
// (sRGB-encoded) and float depth. Rendering is deterministic: the same mesh, camera and options give
// the same bytes.
//
// Cameras follow the LOD runtime's screen-space error convention (include/lodkit/runtime.h): the
// vertical field of view `fov`, and an object-space length e at depth d along the view axis covers
// e * H / (2 d tan(fov / 2)) pixels on an image H pixels high, so a LOD's stated pixel error can be
// checked on a real image.
//
// This module is its own library (lodkit_render), so the core library needs no EGL or GL.
#pragma once

#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "lodkit/mesh.h"
#include "lodkit/runtime.h"  // BoundingSphere, bounding_sphere

namespace lod {

// ---- images ---------------------------------------------------------------------------------------

struct Image {
  uint32_t width = 0, height = 0;
  // width * height * 4 bytes, rows top to bottom, sRGB-encoded RGBA (alpha 255: the background is opaque).
  std::vector<uint8_t> rgba;
  // width * height floats, rows top to bottom (empty when not read back): the depth of the surface
  // seen at each pixel, as its distance from the eye along the view axis (object units);
  // +infinity where nothing was drawn.
  std::vector<float> depth;

  bool covered(uint32_t x, uint32_t y) const { return depth[size_t(y) * width + x] != std::numeric_limits<float>::infinity(); }
  const uint8_t* pixel(uint32_t x, uint32_t y) const { return &rgba[(size_t(y) * width + x) * 4]; }
};

// PNG (8-bit RGBA, deflate level 9, no timestamp: the same image always gives the same bytes).
std::string encode_png(const Image& image);
// Writes atomically (a temporary file in the same folder, then rename).
void write_png(const Image& image, const std::filesystem::path& path);
// Decodes a PNG into RGBA (no depth); bad_input naming `name` when it is not a readable PNG.
Image decode_png(std::span<const uint8_t> bytes, const std::string& name);
Image read_png(const std::filesystem::path& path);

// ---- context --------------------------------------------------------------------------------------

// A headless OpenGL 4.5 core context. Each call that draws or uploads makes it current on the
// calling thread; a context must not be used from two threads at once. The EGL display stays
// initialised until the process exits: displays are shared process-wide, so terminating one would
// end every other context on it. Creating it throws lod::Error
// (bad_input) naming the missing piece when there is no usable EGL driver or GL 4.5 core support,
// for example "no EGL driver: ...", instead of crashing.
class RenderContext {
 public:
  RenderContext();
  ~RenderContext();
  RenderContext(const RenderContext&) = delete;
  RenderContext& operator=(const RenderContext&) = delete;

  const std::string& renderer() const;  // GL_RENDERER, e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"
  const std::string& version() const;   // GL_VERSION
  uint32_t max_samples() const;         // the most MSAA samples per pixel the driver offers

  struct State;
  State& state();  // made current on the calling thread

 private:
  std::unique_ptr<State> state_;
};

// A mesh uploaded to a context's GPU memory, for drawing many times (turntables, image metrics).
// Normals are computed when the mesh has none (area-weighted over the faces around each position,
// so UV seams do not crease). Move-only; must not outlive its context.
class GpuMesh {
 public:
  GpuMesh(RenderContext& context, const Mesh& mesh, const std::string& name = "mesh");
  ~GpuMesh();
  GpuMesh(GpuMesh&& other) noexcept;
  GpuMesh& operator=(GpuMesh&& other) noexcept;
  GpuMesh(const GpuMesh&) = delete;
  GpuMesh& operator=(const GpuMesh&) = delete;

  uint64_t triangle_count() const { return triangles_; }
  bool has_colors() const { return has_colors_; }
  const BoundingSphere& bounds() const { return bounds_; }
  uint32_t buffer(int k) const { return buffers_[k]; }

 private:
  void release();
  RenderContext* context_ = nullptr;
  uint32_t buffers_[4] = {0, 0, 0, 0};  // GL buffer names: positions, normals, colours, indices
  uint64_t triangles_ = 0;
  bool has_colors_ = false;
  BoundingSphere bounds_;
};

// ---- cameras --------------------------------------------------------------------------------------

inline constexpr double default_render_fov = 0.6981317007977318;  // 40 degrees, vertical

struct RenderCamera {
  float3 eye{0, 0, 5};     // object space (meshes are drawn as they are)
  float3 target{0, 0, 0};  // the point at the image centre
  float3 up{0, 1, 0};      // the image's up direction (need not be orthogonal to the view axis)
  double fov = default_render_fov;  // vertical field of view, radians (perspective)
  // > 0: orthographic, showing this many object units from the bottom to the top of the image.
  double ortho_height = 0;
  // Clip distances along the view axis, object units (0 < near < far).
  double near = 0.01, far = 100;
};

// A direction from the target towards the eye, by name: the six axis views "front" (+z, glTF's
// front), "back" (-z), "right" (+x), "left" (-x), "top" (+y), "bottom" (-y); the eight isometric
// views "iso" (= "iso-front-right"), "iso-front-left", "iso-back-right", "iso-back-left" and the same
// with "-below" (from under the model); or three numbers "x,y,z". Throws lod::Error (usage) otherwise.
float3 view_direction(const std::string& name);
// Every name view_direction accepts, axis views then isometric ones.
std::vector<std::string> view_names();

// A camera looking at the sphere's centre from `direction` (towards the eye; need not be unit),
// as close as it can be with the whole sphere in the image (aspect = width / height). With
// `orthographic`, the image shows the sphere's diameter across its smaller side. Up is +y, except for
// views along y (up is -z from above, +z from below, so the front stays at the bottom of a top view).
RenderCamera fit_camera(const BoundingSphere& sphere, float3 direction, double aspect, double fov = default_render_fov,
                        bool orthographic = false);

// Frame `frame` of `frames` (0 <= frame < frames) of a turntable: the camera circles the sphere
// around +y, starting in front (+z) and turning by 360 / frames degrees per frame towards +x, at
// `elevation` radians above the horizon, fitted as fit_camera does.
RenderCamera turntable_camera(const BoundingSphere& sphere, uint32_t frame, uint32_t frames, double aspect,
                              double elevation = 0.3490658503988659, double fov = default_render_fov);

// `count` directions spread evenly over the unit sphere (a Fibonacci spiral, deterministic).
std::vector<float3> sphere_directions(uint32_t count);

// Where an object-space point lands on a width x height image: pixel coordinates from the top-left
// corner (pixel (i, j) covers [i, i + 1) x [j, j + 1)) and its depth along the view axis.
float3 project(const RenderCamera& camera, uint32_t width, uint32_t height, const float3& point);

// ---- drawing --------------------------------------------------------------------------------------

enum class Shading {
  smooth,  // interpolated vertex normals
  flat,    // one normal per triangle (its plane)
};

struct RenderOptions {
  uint32_t width = 1024, height = 768;  // pixels
  // MSAA samples per pixel, 1 for none (exact coverage at pixel centres, as the image metrics use);
  // clamped to the driver's maximum.
  uint32_t samples = 4;
  Shading shading = Shading::smooth;
  // Lambert shading with a headlight (a directional light along the view axis), both sides lit:
  // colour = albedo * (ambient + (1 - ambient) * max(0, n . l)).
  float ambient = 0.2f;
  // Albedo: the mesh's vertex colours (linear RGB) when it has them, else base_color.
  bool vertex_colors = true;
  float3 base_color{0.6f, 0.6f, 0.6f};  // linear RGB
  // The vertex colours are a heat map (lodkit compare --heatmap): required, and lit by a softer
  // headlight (ambient 0.6) so the ramp stays readable; a face turned to the camera shows its colour exactly.
  bool heatmap = false;
  // Triangle edges drawn over the shading (from barycentrics in the fragment shader).
  bool wireframe = false;
  float wire_width = 1.0f;                // pixels
  float3 wire_color{0.02f, 0.02f, 0.02f};  // linear RGB
  float3 background{1, 1, 1};              // linear RGB
  bool read_depth = true;                  // fill Image::depth
};

// Draws an uploaded mesh. Throws lod::Error: usage for a zero or too large size or an invalid
// camera; bad_input when heatmap is asked of a mesh without vertex colours.
Image render(RenderContext& context, const GpuMesh& mesh, const RenderCamera& camera, const RenderOptions& options = {});
// Uploads, draws and frees: for a single picture.
Image render(RenderContext& context, const Mesh& mesh, const RenderCamera& camera, const RenderOptions& options = {});

// ---- text and contact sheets ----------------------------------------------------------------------

// A TrueType font (FreeType) for labels. The default is DejaVu Sans from Debian's fonts-dejavu-core;
// a missing font file is a bad_input error naming the file and the package.
class Font {
 public:
  explicit Font(const std::filesystem::path& path = default_font_path());
  ~Font();
  Font(const Font&) = delete;
  Font& operator=(const Font&) = delete;

  static std::filesystem::path default_font_path();
  // Draws UTF-8 `text` with its baseline starting at (x, y) (pixels from the top-left), `size` pixels
  // per em, blending `color` (sRGB bytes) by the glyphs' coverage. Returns the advance in pixels.
  int draw(Image& image, int x, int y, const std::string& text, uint32_t size, const uint8_t color[3]) const;
  int width(const std::string& text, uint32_t size) const;  // advance of `text` in pixels
  // At `size`: pixels from the baseline up to the font's ascender, and from its ascender down to its
  // descender (a line's height without spacing).
  int ascent(uint32_t size) const;
  int line_height(uint32_t size) const;

 private:
  struct Face;
  std::unique_ptr<Face> face_;
};

struct SheetOptions {
  uint32_t width = 1024, height = 768;  // pixels, the whole sheet
  uint32_t columns = 0;                 // panels per row; 0: the most square grid
  uint32_t label_size = 0;              // label text size in pixels; 0: from the panel height
};

// The size of each panel of a sheet of `panels` panels, below which its label strip goes.
struct SheetLayout {
  uint32_t columns = 1, rows = 1;
  uint32_t panel_width = 0, panel_height = 0;  // the rendered picture of each panel
  uint32_t label_height = 0;                   // the strip under it
  uint32_t label_size = 0;
};
SheetLayout sheet_layout(uint32_t panels, const SheetOptions& options);

// Places each image (panel_width x panel_height, from sheet_layout) in the grid, row by row, with its
// label under it, on a white sheet.
Image contact_sheet(std::span<const Image> panels, std::span<const std::string> labels, const SheetOptions& options,
                    const Font& font);

// A colour ramp legend for heat maps (lod::heat_color from 0 to 1) in the image's bottom-left
// corner, labelled with `low` and `high` at its ends.
void draw_heat_legend(Image& image, const Font& font, const std::string& low, const std::string& high);

// ---- image metrics --------------------------------------------------------------------------------

// Two images of the same size with depth, compared pixel by pixel. Coverage is a finite depth.
struct ImageDifference {
  uint64_t covered_a = 0, covered_b = 0;
  uint64_t covered_both = 0;
  uint64_t covered_one = 0;  // pixels covered in exactly one image: the silhouette difference
  // covered_one / (pixels covered in either); 0 when neither covers anything.
  double coverage_difference = 0;
  // |depth a - depth b| over the pixels covered in both (object units); 0 when there are none.
  double max_depth_difference = 0, mean_depth_difference = 0;
  // The largest distance, in pixels, from a silhouette pixel of either image (a covered pixel with an
  // uncovered 4-neighbour, or on the image border) to the nearest silhouette pixel of the other: how
  // far the outline moved. 0 when neither covers anything; +infinity when only one does.
  double silhouette_displacement_px = 0;
};
// Throws lod::Error (usage) when the sizes differ or either image has no depth.
ImageDifference compare_images(const Image& a, const Image& b);

struct ViewDifferenceOptions {
  uint32_t views = 8;                     // directions from sphere_directions
  uint32_t width = 512, height = 512;     // pixels
  double fov = default_render_fov;        // radians; ignored with orthographic
  bool orthographic = false;
};

struct ViewsDifference {
  std::vector<RenderCamera> cameras;          // one per view, fitted to a's bounding sphere
  std::vector<ImageDifference> views;         // one per camera
  double max_coverage_difference = 0;
  double max_depth_difference = 0;
  double mean_depth_difference = 0;           // over every view's pixels covered in both
  double max_silhouette_displacement_px = 0;
};

// Renders both meshes from the same cameras (no MSAA, so coverage is exact at pixel centres) and
// compares each pair of images: an image-based check of a LOD against its source, or of popping
// between two frames of a transition.
ViewsDifference compare_views(RenderContext& context, const Mesh& a, const Mesh& b, const ViewDifferenceOptions& options = {});

}  // namespace lod
