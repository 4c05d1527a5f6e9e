// lodkit: reading and writing meshes and scenes (OBJ, PLY, OFF, STL, glTF 2.0).
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "lodkit/mesh.h"

namespace lod {

enum class FileFormat { obj, ply, off, stl, gltf, glb };

// From the extension (case-insensitive); throws lod::Error (usage) for an unknown one.
FileFormat format_from_path(const std::filesystem::path& path);
const char* format_name(FileFormat format);
// The buffer file write_gltf writes beside a .gltf at `path` (its stem + ".bin"); empty for any other
// extension, which need not be a mesh format (a .glb holds its buffer).
std::filesystem::path gltf_buffer_path(const std::filesystem::path& path);
// Likewise the MTL library write_mesh writes beside an .obj whose mesh has material looks (its stem
// + ".mtl"); empty for any other extension.
std::filesystem::path obj_library_path(const std::filesystem::path& path);
// The MTL libraries the OBJ at `path` names (its mtllib statements, as its reader resolves them),
// those that are there: files it reads, which writing over would change.
std::vector<std::filesystem::path> obj_material_libraries(const std::filesystem::path& path);

struct ReadOptions {
  // Called now and then with the fraction of the input consumed, in [0, 1]. May be empty.
  std::function<void(double fraction)> progress;
  // Worker threads a reader may use (OBJ parses pieces of a large file in parallel); 0 means one per
  // hardware thread. The result never depends on it.
  unsigned threads = 0;
  // Called with each problem the reader let pass (a glTF extension the file requires that lodkit
  // does not know), as a sentence naming the file. May be empty.
  std::function<void(const std::string& message)> warning;
};

struct WriteOptions {
  bool binary = true;  // PLY and STL: binary little-endian (true) or ASCII (false)
  // glTF: geometry, skins and animation compressed with EXT_meshopt_compression (gltfpack -c's
  // codec) without quantization: readers get back the same values (a triangle may start at another
  // corner). The extension is then required: three.js, Babylon.js and lodkit read it (gltfpack 0.18
  // does not).
  bool meshopt_compression = false;
  // With `meshopt_compression`: KHR_meshopt_compression instead, its vertex streams in the codec's
  // version 1 (lodkit's own encoder: 2-8% smaller files on the bench's meshes), for loaders that
  // implement the KHR extension; still exact.
  bool meshopt_khr = false;
  // glTF: vertex streams in fewer bits (KHR_mesh_quantization, then required), as gltfpack does by
  // default. Positions go on one grid for the whole document, `position_bits` per axis (1 to 16) in
  // unsigned shorts, the same step on every axis. Each node drawing such a mesh takes the grid's
  // offset and scale (a new child node carries them where the node has children, a camera, a light
  // or animated transforms), each skin in its inverse bind matrices, each GPU instance in its
  // transform. Morph target positions go on the same step in shorts, their normal and tangent
  // displacements (within [-1, 1]) in normalized bytes. Normals and tangents in normalized bytes;
  // UVs in [0, 1] in normalized unsigned shorts; colours in [0, 1] and skin weights (summing to
  // exactly 255) in normalized unsigned bytes; rotation keyframes in normalized shorts; with
  // `meshopt_compression` too, translation and scale keyframes through meshopt's EXPONENTIAL filter
  // (16-bit mantissas, one exponent per key) and rotation keyframes through its QUATERNION filter
  // (16 bits); other streams stay as they are. Positions stay floats in a mesh that a point or line primitive,
  // skinned GPU instancing or a skin shared with such a mesh ties to its own space.
  bool quantize = false;
  // With `quantize`: how far a reduced animation curve may move what it animates, as a fraction of
  // the scene's extent at rest (README, -q): 2^-12 by default (0.45 mm on a 1.85 m character);
  // larger drops more keys, 0 keeps every key a curve needs exactly. 0 to 1.
  double animation_error = 1.0 / 4096;
  // With `meshopt_compression` and `quantize`: normals and tangents through meshopt's OCTAHEDRAL
  // filter too (8 bits, or `normal_bits`), as gltfpack -cc: about a third fewer bytes for them. The
  // filter codes the input's floats (the same codes as gltfpack -cc's), within 1.35 degrees of them
  // at 8 bits, where the normalized bytes `quantize` alone stores are within 0.4 degrees.
  bool compress_more = false;
  // glTF: each triangle primitive's vertex streams and indices as a Draco stream
  // (KHR_draco_mesh_compression, then required) at Draco's default compression level 7, as
  // draco_transcoder writes it: positions quantized to `position_bits`, normals to 10 bits, UVs to
  // 12, colours to 8, tangents and skin weights to 12; joint indices and connectivity exact.
  // Edgebreaker may renumber a primitive's vertices and triangles, and drops those with a repeated
  // corner; morph targets and other streams outside the Draco stream follow the renumbering (a
  // primitive where two vertices decode alike, whose outside streams could not be told apart, is
  // encoded sequentially, in place). A stream whose range overflows a float is stored exactly
  // (libdraco 1.5.5 crashes quantizing it), and a primitive libdraco cannot round-trip (a triangle
  // with three equal corners) is written plain. With `quantize`, positions on its grid go into the
  // Draco stream as their grid coordinates, exactly, and morph targets, animation and the streams
  // outside are stored as `quantize` says; Draco quantizes the other vertex streams. With
  // `meshopt_compression`, meshopt compresses what Draco does not (animation, morph targets).
  bool draco = false;
  int position_bits = 14;
  // With `quantize` or `draco`: bits per normal and tangent component, 8 to 16, as gltfpack's -vn;
  // 0 for the default, 8 under `quantize` (normalized bytes) and 10 in Draco. Above 8, `quantize`
  // stores normalized shorts on multiples of 2^(16 - bits) (+-1 stay exact; the zero low bits are
  // for gzip or Brotli over the file: the meshopt codec codes whole bytes and gains nothing from
  // them), morph targets' normal and tangent displacements likewise, and
  // `compress_more`'s octahedral filter takes shorts of that many bits. Smooth, shiny surfaces show
  // the bytes' 0.4 degrees as banding; 12 bits are within 0.03 degrees.
  int normal_bits = 0;
  // With `quantize` or `draco`: bits per UV component, 1 to 16, as gltfpack's -vt; 0 for the
  // default, 16 under `quantize` and 12 in Draco. Below 16, `quantize` stores every UV set a
  // texture samples on a box (as it does for sets outside [0, 1]), in normalized unsigned shorts
  // from 0 to 2^bits - 1, which the meshopt codec packs in fewer bits (gltfpack -c's default is
  // 12); a set no box can hold (README, -q) keeps 16 bits or floats.
  int uv_bits = 0;
  // Text formats print floats with the shortest representation that reads back bit-exact.
};

// ---- glTF scene model --------------------------------------------------------------------------
// Everything lodkit reads from a glTF file. Meshes are split into primitives; the rest (nodes,
// skins, animations) is exposed read-only for later stages, and the source document is kept so that
// writing changes only the primitives' geometry: materials, textures (image bytes identical), node
// transforms, skins and animations are written back as they were.

// A glTF morph target: per-vertex displacements, added with the mesh's weight.
struct MorphTarget {
  std::vector<float3> positions;  // one per vertex
  std::vector<float3> normals;    // empty, or one per vertex
  std::vector<float3> tangents;   // empty, or one per vertex (of the tangent's xyz)
  friend bool operator==(const MorphTarget&, const MorphTarget&) = default;
};
// A target's streams, for code that treats them alike (positions first; the others may be empty).
inline constexpr std::array<std::vector<float3> MorphTarget::*, 3> morph_streams = {
    &MorphTarget::positions, &MorphTarget::normals, &MorphTarget::tangents};

struct Primitive {
  Mesh mesh;                    // triangles only; materials[] is empty (the primitive has one material)
  // Written with the geometry when the glTF primitive has no targets of its own (scenes built by
  // lodkit, such as lodkit lod --morph's geomorphs); not filled by the reader.
  std::vector<MorphTarget> targets;
  // Scenes built by lodkit: an earlier scene primitive whose vertex streams (identical to this
  // mesh's) this one reuses, so the file holds one vertex buffer and an index buffer per primitive
  // (lodkit lod --shared-vertices). -1: its own.
  int32_t shares_vertices_with = -1;
  // Each vertex's vertex in the source glTF primitive, for the streams lodkit does not model
  // (morph targets, attributes such as TEXCOORD_4 or _ID): the writer gathers them through it. Set
  // by whatever renumbers the vertices (lodkit optimize, the skinned chain's level 0). Empty: the
  // vertices are the source's own, in order, while their count is unchanged, and otherwise those
  // streams are dropped.
  std::vector<uint32_t> source_vertices;
  // Vertices that moved (a simplification, lod::vertex_blends): source_vertices then holds three
  // source vertices per vertex, blended with these weights. Float and normalized streams are
  // interpolated, other integer ones (ids) take the heaviest vertex's value. Empty: one each.
  std::vector<std::array<float, 3>> source_weights;
  // How many of the source glTF primitive's morph targets are written (the first ones), with the
  // weights and weight clips of the nodes drawing its mesh cut to match; every primitive of a glTF
  // mesh must say the same. lodkit simplify drops lod --morph's geomorph (the last) from a level it
  // changes, and keeps the blend shapes before it.
  uint32_t source_target_count = UINT32_MAX;
  uint32_t gltf_mesh = 0;       // index of the glTF mesh this primitive belongs to
  uint32_t gltf_primitive = 0;  // index within that mesh
  int32_t material = -1;        // glTF material index, -1 for none
};

struct Node {
  std::string name;
  int32_t parent = -1;
  std::vector<int32_t> children;
  int32_t mesh = -1;  // glTF mesh index (a source node written back takes a new mesh, not another of the source's)
  int32_t skin = -1;
  // Local transform: `matrix` (column-major) when has_matrix, else T * R * S.
  bool has_matrix = false;
  std::array<float, 16> matrix = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  float3 translation;
  float4 rotation = {0, 0, 0, 1};  // unit quaternion x, y, z, w
  float3 scale = {1, 1, 1};
  // The MSFT_lod extension's coarser-level node ids (lodkit lod's chains), and the node's extras as
  // JSON text ("" for none). The glTF reader fills both; the writer writes them, and leaves a source
  // node's own MSFT_lod and extras as they were where they are empty.
  std::vector<int32_t> lod_ids;
  std::string extras_json;
  // EXT_mesh_gpu_instancing (gltfpack -mi, forests and crowds): the node's mesh is drawn once per
  // instance, at the node's world transform times the instance's T * R * S. Empty: drawn once.
  // The reader fills it and flatten() places every instance; the writer keeps the source's.
  struct GpuInstance {
    float3 translation;
    float4 rotation = {0, 0, 0, 1};
    float3 scale = {1, 1, 1};
  };
  std::vector<GpuInstance> gpu_instances;
  // A node lodkit adds (a LOD level of morphing meshes): its mesh's morph targets are these source
  // nodes' in turn, and take their weights and weight clips. One node's channels are copied (the
  // same samplers); several nodes' become one channel per clip (lod::concatenate_weights). Targets
  // past theirs (a geomorph) take weight 0. Empty (or negative ids): none.
  std::vector<int32_t> morph_weights_of;
  // KHR_node_visibility. `visible` false hides the node and everything below it: flatten() leaves
  // them out, as a viewer does. `has_visibility`: the node has the extension (shown or hidden) or a
  // clip switches it (a KHR_animation_pointer to ".../KHR_node_visibility/visible"), so what is
  // below it shows and hides with it. The reader fills both; the writer writes `visible` false (and
  // true where the source node was hidden), the extension declared in extensionsUsed.
  bool visible = true;
  bool has_visibility = false;
};

struct Skin {
  std::string name;
  std::vector<int32_t> joints;  // node indices
  std::vector<std::array<float, 16>> inverse_bind_matrices;  // column-major, one per joint
  int32_t skeleton = -1;
};

enum class AnimationPath { translation, rotation, scale, weights };
enum class Interpolation { step, linear, cubic_spline };

struct AnimationChannel {
  int32_t node = -1;
  AnimationPath path = AnimationPath::translation;
  Interpolation interpolation = Interpolation::linear;
  std::vector<float> times;   // seconds, one per key
  std::vector<float> values;  // flattened; per key: components (x3 for cubic_spline: in-tangent, value, out-tangent)
  uint32_t components = 3;    // 3 for translation/scale, 4 for rotation, morph-target count for weights
};

// A channel's components at `time`, clamped to its keys (NaN: the first key), each interpolated on
// its own (step, linear or glTF's cubic Hermite spline; rotations want a slerp instead). With `slope`,
// also their derivatives per second on the interval after `time` (or before it, `after` false): 0
// outside the keys and for step. The channel must be well formed (values for every key).
void sample_components(const AnimationChannel& ch, float time, float* out, float* slope = nullptr, bool after = true);

// One weights channel for a mesh whose morph targets are several nodes' in turn: per node, its
// weights channel in the clip, or none (then its `rest` weights hold). Keys at the union of the
// channels' times, and exact: step channels stay step; linear and cubic-spline ones become the kind
// that represents both (a cubic spline split at a new key keeps its shape: the value and slope there
// are the key's value and tangents). nullopt without any channel, when step mixes with the others,
// or when a channel's weight count is not its node's `rest` count.
struct WeightsSource {
  const AnimationChannel* channel = nullptr;
  std::vector<float> rest;  // the node's weights at rest, one per morph target
};
std::optional<AnimationChannel> concatenate_weights(const std::vector<WeightsSource>& sources);

struct Animation {
  std::string name;
  std::vector<AnimationChannel> channels;
};

// The weights channel of `clip` that drives `node` (the first, should there be several), or null.
const AnimationChannel* weights_channel(const Animation& clip, int32_t node);

struct GltfSource;  // opaque: the parsed source document (src/io/gltf.cpp)

struct Scene {
  std::vector<Primitive> primitives;
  std::vector<Node> nodes;
  std::vector<int32_t> roots;  // root nodes of the default scene
  std::vector<Skin> skins;
  // Node channels. From glTF, a mesh's weights animated by KHR_animation_pointer appear as the
  // weights channel of each node drawing the mesh without weights of its own (after the clip's
  // node channels); the writer keeps the source's channels, pointers included.
  std::vector<Animation> animations;
  std::vector<std::string> material_names;  // by glTF material index
  // By glTF material index, as material_names: in a scene made from a mesh that has them
  // (scene_from_mesh), what the glTF writer makes those materials look like; from a glTF source
  // (which the writer keeps as it is), its materials' factors and external texture files on UV set
  // 0, for a mesh flattened from it (an OBJ's MTL library; source_material_looks adds the embedded
  // images).
  std::vector<MaterialLook> material_looks;
  uint32_t image_count = 0;
  uint32_t texture_count = 0;
  // glTF meshes in the source document, points and lines included: a primitive with a gltf_mesh
  // from here on makes a new mesh.
  uint32_t gltf_mesh_count = 0;
  // The source document's extensionsUsed as declared, the compression extensions the reader decoded
  // (and the writer drops) included: what `lodkit info` reports.
  std::vector<std::string> extensions_used;
  std::shared_ptr<const GltfSource> source;  // non-null when read from glTF
  std::string name;                           // the file it was read from, for messages
};

// Takes nodes out of a scene read from glTF, with what refers to them: parents' children, the
// default and other scenes' roots, MSFT_lod ids, and the clips' channels that move or switch them
// (KHR_animation_pointer's too); the other nodes are renumbered there and in skins, clips and
// Node::morph_weights_of, in the scene and in the document it writes back. Only the source's nodes
// go; nodes added after them are renumbered (what their extras say is the caller's). lodkit lod
// drops an earlier run's level nodes this way, which its new levels replace. A node stays where
// something else needs it: it has a camera or an extension other than MSFT_lod,
// KHR_node_visibility and EXT_mesh_gpu_instancing, a skin uses it, a node takes its morph weights,
// or one of its children stays (an added node below it among them). All stay when the document
// declares an extension that might refer to nodes by index (one lodkit does not know). The caller
// erases only nodes whose meshes it no longer draws. Returns each node's new index, -1 for those
// erased.
std::vector<int32_t> erase_nodes(Scene& scene, const std::vector<bool>& erase);

// ---- files --------------------------------------------------------------------------------------
// Format follows the extension. Errors throw lod::Error: bad_input naming the file and the line or
// byte offset; usage for unknown extensions. Directories and unreadable paths are bad_input.
Mesh read_mesh(const std::filesystem::path& path, const ReadOptions& options = {});
Scene read_scene(const std::filesystem::path& path, const ReadOptions& options = {});

// What a write did, for reports.
struct WriteReport {
  uint64_t bytes = 0;  // every file written (a .gltf's .bin, an .obj's .mtl, images beside an OBJ or PLY too)
  // WriteOptions::draco: triangle primitives by how they went into Draco. Edgebreaker; sequential,
  // in place (two vertices decode alike while streams outside the Draco stream must follow them,
  // or libdraco's Edgebreaker could not take the mesh); plain, not in Draco (libdraco could not
  // round-trip it).
  uint32_t draco_edgebreaker = 0, draco_sequential = 0, draco_plain = 0;
};

// Writes atomically (temporary file in the same folder, then rename). A glTF scene keeps everything
// it was read with; writing a Mesh to glTF makes a one-node scene. An OBJ or PLY gets the images its
// material looks embed as files beside it, OUT_0.png, OUT_1.jpg, ... (MaterialLook::images).
WriteReport write_mesh(const Mesh& mesh, const std::filesystem::path& path, const WriteOptions& options = {});
WriteReport write_scene(const Scene& scene, const std::filesystem::path& path, const WriteOptions& options = {});

// Every primitive instance of the default scene that is shown (Node::visible), in world space, merged into one mesh.
// Material ids are glTF material indices (+1, so 0 means "no material"); names follow. A skinned
// mesh is in its bind pose, in its own space, unless every joint carries the same matrix at rest
// (world times inverse bind matrix: the skeleton moved after binding, or a quantized file's grid,
// -q or gltfpack's): that matrix then places it, where a viewer draws it. A vertex stream is kept
// when every instance has it, or with fill_streams when any has it: the others then get neutral
// values (lod::fill_streams), for a join whose result goes back to its parts, each with its own
// streams (keep_streams). Influences are never made up.
struct FlattenOptions {
  bool fill_streams = false;
};
Mesh flatten(const Scene& scene, const FlattenOptions& options = {});
// The primitives flatten(scene) draws (indices into Scene::primitives), each once, in the order
// they first appear in it.
std::vector<size_t> flattened_primitives(const Scene& scene);

// The morph targets of flatten(scene), per vertex of it: each node drawing morphing primitives
// contributes its glTF mesh's targets (source_morph_targets' displacements), taken to world space
// with the vertices (a normal's or tangent's displacement to where the displaced one goes; none
// unless flatten keeps those streams) and zero on every other instance's vertices; the nodes'
// targets follow one another, so a node taking all their weights in turn (Node::morph_weights_of)
// drives them.
struct FlatMorphTargets {
  std::vector<MorphTarget> targets;
  std::vector<int32_t> nodes;  // the morphing nodes, in flatten's order (-1: a scene without nodes)
  std::vector<size_t> first;   // per node, its first target in `targets`
};
FlatMorphTargets flatten_morph_targets(const Scene& scene);
// A one-primitive scene around a mesh (no source document); materials become primitives.
Scene scene_from_mesh(const Mesh& mesh);
// A mesh's triangles by material id, ascending, each part with only the vertices its triangles use,
// in the mesh's order: part vertex k is mesh vertex `vertices[k]`. Without material ids: one part
// (id 0) with every vertex. The parts drop the per-triangle streams (materials, groups).
struct MaterialPart {
  uint32_t material = 0;
  Mesh mesh;
  std::vector<uint32_t> vertices;
};
std::vector<MaterialPart> split_by_material(const Mesh& mesh);

// Per vertex of a glTF-read scene primitive, a class: two vertices share one exactly when the
// streams lodkit does not model (morph targets, attributes such as TEXCOORD_4 or _ID) are
// byte-identical for their source vertices (Primitive::source_vertices, or the vertices themselves
// while their count is the source's). Empty when the primitive has no such streams, or they will
// not be written. A weld that keeps classes apart (WeldOptions::vertex_classes) keeps them exact.
std::vector<uint32_t> source_vertex_classes(const Scene& scene, size_t primitive);

// The files a scene read from glTF names beside it: its external buffers and images, resolved
// against its folder (data: URIs and the GLB chunk are none). Writing over one would change the
// input. Empty for a scene not read from glTF.
std::vector<std::filesystem::path> source_files(const Scene& scene);

// Scene::material_looks, and for a scene read from glTF the images its document embeds (BIN chunk,
// data: URIs) as those materials' textures (MaterialLook::images), for a mesh flattened from it:
// the reader leaves them in the document, which a glTF written from the scene keeps as it is.
std::vector<MaterialLook> source_material_looks(const Scene& scene);

// The source glTF primitive's morph targets (POSITION, NORMAL and TANGENT displacements; other
// semantics are not decoded), those it keeps (Primitive::source_target_count), per vertex of the
// scene primitive (through Primitive::source_vertices). Empty when it has none or its vertices are
// not the source's.
std::vector<MorphTarget> source_morph_targets(const Scene& scene, size_t primitive);

// ---- per format, in memory (used by the file functions, tests and fuzzers) ----------------------
// `name` is used in error messages. Writers append to `out`.
// `material_libraries`, when given, gets the text of each mtllib statement, in file order.
Mesh read_obj(std::span<const uint8_t> bytes, const std::string& name, const ReadOptions& options = {},
              std::vector<std::string>* material_libraries = nullptr);
// A Wavefront MTL material library (what an OBJ's mtllib names): each material as glTF's
// metallic-roughness core sees it (Kd, d or Tr, Ke, Pm, Pr or Ns; map_Kd, norm or map_Bump,
// map_Ke), texture paths resolved against `folder`.
struct MtlMaterial {
  std::string name;
  MaterialLook look;
};
std::vector<MtlMaterial> read_mtl(std::span<const uint8_t> bytes, const std::string& name,
                                  const std::filesystem::path& folder = {});
// The MTL library of `mesh`'s material looks, those its triangles use, for an OBJ in `folder`
// (texture paths relative to it where they can be): read_mtl gives the looks back.
void write_mtl(const Mesh& mesh, std::string& out, const std::filesystem::path& folder);
// `textures`, when given, gets the file of each "comment TextureFile" header line (MeshLab's), in order:
// texnumber k's texture.
Mesh read_ply(std::span<const uint8_t> bytes, const std::string& name, const ReadOptions& options = {},
              std::vector<std::string>* textures = nullptr);
Mesh read_off(std::span<const uint8_t> bytes, const std::string& name, const ReadOptions& options = {});
Mesh read_stl(std::span<const uint8_t> bytes, const std::string& name, const ReadOptions& options = {});
// External buffer and image URIs are resolved against base_dir; with an empty base_dir only data:
// URIs and the GLB binary chunk are allowed.
Scene read_gltf(std::span<const uint8_t> bytes, const std::string& name, const std::filesystem::path& base_dir = {},
                const ReadOptions& options = {});

void write_obj(const Mesh& mesh, std::string& out, const WriteOptions& options = {});
// A PLY links its materials' base colour textures as MeshLab does (TextureFile comments, texnumber),
// each texture named by its path from `folder`, where the file goes.
void write_ply(const Mesh& mesh, std::string& out, const WriteOptions& options = {}, const std::filesystem::path& folder = {});
void write_off(const Mesh& mesh, std::string& out, const WriteOptions& options = {});
void write_stl(const Mesh& mesh, std::string& out, const WriteOptions& options = {});
// glTF: `path` decides .gltf (JSON + a .bin beside it) or .glb; every file is written atomically.
WriteReport write_gltf(const Scene& scene, const std::filesystem::path& path, const WriteOptions& options = {});

// A whole file's bytes, read-only: memory-mapped (no copy, no zero-fill: multi-gigabyte scans load
// at page-cache speed), or read into memory when the file cannot be mapped. Move-only.
class FileBytes {
 public:
  FileBytes() = default;
  ~FileBytes();
  FileBytes(FileBytes&& other) noexcept;
  FileBytes& operator=(FileBytes&& other) noexcept;
  FileBytes(const FileBytes&) = delete;
  FileBytes& operator=(const FileBytes&) = delete;

  const uint8_t* data() const { return data_; }
  size_t size() const { return size_; }
  const uint8_t* begin() const { return data_; }
  const uint8_t* end() const { return data_ + size_; }
  operator std::span<const uint8_t>() const { return {data_, size_}; }

 private:
  friend FileBytes read_file_bytes(const std::filesystem::path& path);
  const uint8_t* data_ = nullptr;
  size_t size_ = 0;
  bool mapped_ = false;
  std::vector<uint8_t> copy_;  // when not mapped
};

// Reads a whole file; bad_input naming the path if it is missing, a directory or unreadable.
FileBytes read_file_bytes(const std::filesystem::path& path);
// Atomic write: a temporary file in the same folder, then rename over `path`.
void write_file_atomic(const std::filesystem::path& path, std::span<const uint8_t> bytes);
void write_file_atomic(const std::filesystem::path& path, const std::string& bytes);

}  // namespace lod
