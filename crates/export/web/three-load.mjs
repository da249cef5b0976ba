// Loads .glb files with three.js's GLTFLoader (in node, no rendering) and
// checks that the morph-target animation drives the weights as intended:
// at the time of exported frame k the mesh's influences are one-hot on target k-1.
//   node three-load.mjs a.glb [b.glb ...]   -> one JSON line per file; exit 1 on failure
import { readFile } from 'node:fs/promises';
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';

let failed = false;
for (const file of process.argv.slice(2)) {
  const out = { file };
  try {
    const buf = await readFile(file);
    const ab = buf.buffer.slice(buf.byteOffset, buf.byteOffset + buf.byteLength);
    const gltf = await new Promise((ok, err) => new GLTFLoader().parse(ab, '', ok, err));
    let mesh = null;
    gltf.scene.traverse((o) => { if (o.isMesh) mesh = o; });
    out.vertices = mesh.geometry.attributes.position.count;
    const targets = mesh.geometry.morphAttributes.position?.length ?? 0;
    out.targets = targets;
    out.clips = gltf.animations.length;
    if (targets > 0) {
      const clip = gltf.animations[0];
      const times = clip.tracks[0].times;
      const mixer = new THREE.AnimationMixer(gltf.scene);
      const action = mixer.clipAction(clip);
      action.setLoop(THREE.LoopOnce);
      action.clampWhenFinished = true;
      action.play();
      let bad = 0;
      // Keys: one per exported frame, then a closing key repeating the last.
      for (let k = 0; k < times.length; k++) {
        mixer.setTime(times[k]);
        const w = mesh.morphTargetInfluences;
        for (let t = 0; t < targets; t++) {
          const want = k >= 1 && t === Math.min(k - 1, targets - 1) ? 1 : 0;
          if (Math.abs(w[t] - want) > 1e-3) bad++;
        }
      }
      out.badWeights = bad;
      if (bad > 0) failed = true;
    }
  } catch (e) {
    out.error = String(e);
    failed = true;
  }
  console.log(JSON.stringify(out));
}
process.exit(failed ? 1 : 0);
