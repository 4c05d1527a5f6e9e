// A viewer's reading of a glTF for lodkit's tests: three.js's GLTFLoader (with meshoptimizer's
// JavaScript decoder for EXT_ and KHR_meshopt_compression) parses the file, and this prints as JSON
// what a renderer would get: per glTF mesh, each primitive's geometry (every attribute's item size,
// normalized flag and values as three.js holds them, the morph targets' values, the indices), per
// clip each track's name, times and values, and what its default scene draws: each mesh's name
// and index count.
import { readFileSync } from 'node:fs';
import { GLTFLoader } from 'three/examples/jsm/loaders/GLTFLoader.js';
import { MeshoptDecoder } from 'meshoptimizer';

await MeshoptDecoder.ready;
const bytes = readFileSync(process.argv[2]);
const loader = new GLTFLoader().setMeshoptDecoder(MeshoptDecoder);
const gltf = await loader.parseAsync(bytes.buffer.slice(bytes.byteOffset, bytes.byteOffset + bytes.byteLength), '');
const values = (a) => Array.from(a.array);
const primitives = [];
(await gltf.parser.getDependencies('mesh')).forEach((object, mesh) => {
  (object.isGroup ? object.children : [object]).forEach((part, primitive) => {
    const g = part.geometry;
    const attributes = {}, targets = {};
    for (const [name, a] of Object.entries(g.attributes)) attributes[name] = { itemSize: a.itemSize, normalized: a.normalized, values: values(a) };
    for (const [name, list] of Object.entries(g.morphAttributes)) targets[name] = list.map(values);
    primitives.push({ mesh, primitive, attributes, targets, indices: g.index ? values(g.index) : null });
  });
});
const clips = gltf.animations.map((clip) => clip.tracks.map((t) => ({ name: t.name, times: Array.from(t.times), values: Array.from(t.values) })));
const drawn = [];
gltf.scene.traverse((o) => {
  if (o.isMesh) drawn.push({ name: o.name, indices: o.geometry.index ? o.geometry.index.count : o.geometry.attributes.position.count });
});
process.stdout.write(JSON.stringify({ primitives, clips, drawn }));
