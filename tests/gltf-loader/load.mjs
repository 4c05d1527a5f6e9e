// A second glTF reader for lodkit's tests: glTF-Transform reads the file (KHR_draco_mesh_compression
// through Google's draco3dgltf WebAssembly decoder, EXT_meshopt_compression through
// meshoptimizer's JavaScript decoder, KHR_mesh_quantization as stored) and this prints every mesh
// primitive's streams as JSON, in document order with its mesh and primitive index: per attribute
// and morph target its component type, normalized flag and values as stored; the indices. With
// --textures: the materials' texture references instead.
import { NodeIO } from '@gltf-transform/core';
import { ALL_EXTENSIONS } from '@gltf-transform/extensions';
import draco3d from 'draco3dgltf';
import { MeshoptDecoder } from 'meshoptimizer';

const stream = (a) => ({ type: a.getComponentType(), normalized: a.getNormalized(), values: Array.from(a.getArray()) });

await MeshoptDecoder.ready;
const io = new NodeIO().registerExtensions(ALL_EXTENSIONS).registerDependencies({
  'draco3d.decoder': await draco3d.createDecoderModule(),
  'meshopt.decoder': MeshoptDecoder,
});
const doc = await io.read(process.argv[2]);
if (process.argv[3] === '--textures') {
  // Per material, each texture reference (core and material extensions': every get*TextureInfo with
  // a texture) as glTF-Transform reads it: its slot, texCoord and KHR_texture_transform.
  const materials = [];
  for (const material of doc.getRoot().listMaterials()) {
    const refs = [];
    for (const owner of [material, ...material.listExtensions()]) {
      const names = new Set();
      for (let o = Object.getPrototypeOf(owner); o; o = Object.getPrototypeOf(o))
        for (const name of Object.getOwnPropertyNames(o)) if (/^get\w+TextureInfo$/.test(name)) names.add(name);
      for (const name of [...names].sort()) {
        const texture = owner[name.replace(/Info$/, '')]?.();
        const info = owner[name]();
        if (!texture || !info) continue;
        const ref = { slot: `${owner.extensionName ?? 'core'}.${name}`, texCoord: info.getTexCoord() };
        const t = info.getExtension('KHR_texture_transform');
        if (t) ref.transform = { offset: t.getOffset(), rotation: t.getRotation(), scale: t.getScale(), texCoord: t.getTexCoord() };
        refs.push(ref);
      }
    }
    materials.push(refs);
  }
  process.stdout.write(JSON.stringify(materials));
  process.exit(0);
}
const out = [];
for (const [m, mesh] of doc.getRoot().listMeshes().entries()) {
  for (const [k, prim] of mesh.listPrimitives().entries()) {
    const p = { mesh: m, primitive: k, attributes: {}, targets: [], indices: null };
    for (const semantic of prim.listSemantics()) p.attributes[semantic] = stream(prim.getAttribute(semantic));
    if (prim.getIndices()) p.indices = Array.from(prim.getIndices().getArray());
    for (const target of prim.listTargets()) {
      const t = {};
      for (const semantic of target.listSemantics()) t[semantic] = stream(target.getAttribute(semantic));
      p.targets.push(t);
    }
    out.push(p);
  }
}
process.stdout.write(JSON.stringify(out));
