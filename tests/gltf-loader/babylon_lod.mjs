// How Babylon.js loads a lodkit LOD chain: its glTF loader reads MSFT_lod progressively, the coarsest
// level first, each finer one replacing it, up to `maxLODsToLoad` levels (MSFT_lod's option). This
// loads FILE with a NullEngine (no GPU) and MAX (default all) and prints, as JSON on the last line,
// the meshes it loaded in order (node names) and what the scene finally draws: each mesh with
// geometry, its name and index count.
import { NullEngine } from '@babylonjs/core/Engines/nullEngine.js';
import { Scene } from '@babylonjs/core/scene.js';
import { ImportMeshAsync, SceneLoader } from '@babylonjs/core/Loading/sceneLoader.js';
import '@babylonjs/loaders/glTF/2.0/index.js';
import { readFileSync } from 'node:fs';

const scene = new Scene(new NullEngine());
const max = process.argv[3] ? Number(process.argv[3]) : 10;
const loaded = [];
let complete;
SceneLoader.OnPluginActivatedObservable.addOnce((loader) => {
  loader.extensionOptions = { MSFT_lod: { maxLODsToLoad: max } };
  complete = new Promise((resolve, reject) => {
    loader.onCompleteObservable.addOnce(resolve);
    loader.onErrorObservable.addOnce(reject);
  });
  loader.onMeshLoadedObservable.add((mesh) => loaded.push(mesh.name));
});
await ImportMeshAsync(new Uint8Array(readFileSync(process.argv[2])), scene, { pluginExtension: '.glb' });
await complete;
const drawn = scene.meshes.filter((m) => !m.isDisposed() && m.getTotalIndices() > 0).map((m) => ({ name: m.name, indices: m.getTotalIndices() }));
console.log(JSON.stringify({ loaded: loaded.filter((name) => name !== '__root__'), drawn }));
