// surfcap report viewer: plays source / transfer / truth side by side.
// An ES module inlined into OUT/index.html; 'three' and OrbitControls resolve
// through the page's import map (data: URLs, so it works from file://).
// Data: window.SURFCAP_VIEW = { fps, stride, nFrames, seqs: [{ label, colour,
//   nVertices, faces (base64 Uint32), centre[3], scale[3], positions (base64
//   Int16, nFrames x nVertices x 3, p = centre + scale * q / 32767) }] }.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';

function decode(b64, Type) {
  const bin = atob(b64);
  const bytes = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
  return new Type(bytes.buffer);
}

function webglAvailable() {
  try {
    const c = document.createElement('canvas');
    return !!(c.getContext('webgl2') || c.getContext('webgl'));
  } catch (e) {
    return false;
  }
}

function start(view) {
  const host = document.getElementById('viewer');
  const counter = document.getElementById('frame');
  const slider = document.getElementById('slider');
  const play = document.getElementById('play');
  if (!webglAvailable()) {
    host.textContent = 'This browser has no WebGL: the 3D view is unavailable.';
    return;
  }
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(1);
  renderer.setSize(host.clientWidth, host.clientHeight);
  host.appendChild(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xf4f4f0);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x667788, 1.6));
  const sun = new THREE.DirectionalLight(0xffffff, 1.8);
  sun.position.set(1, 2, 3);
  scene.add(sun);

  // Meshes side by side along x, each one bounding-box width plus a gap apart.
  const seqs = [];
  const gap = 1.3 * Math.max(...view.seqs.map((s) => 2 * Math.max(s.scale[0], s.scale[2])));
  let x = 0;
  for (const s of view.seqs) {
    const q = decode(s.positions, Int16Array);
    const faces = decode(s.faces, Uint32Array);
    const nv = s.nVertices;
    const geometry = new THREE.BufferGeometry();
    const pos = new THREE.BufferAttribute(new Float32Array(nv * 3), 3);
    geometry.setAttribute('position', pos);
    geometry.setIndex(new THREE.BufferAttribute(faces, 1));
    const material = new THREE.MeshStandardMaterial({ color: s.colour, roughness: 0.7, side: THREE.DoubleSide });
    const mesh = new THREE.Mesh(geometry, material);
    mesh.position.set(x - s.centre[0], 0, -s.centre[2]);
    x += gap;
    scene.add(mesh);
    seqs.push({ s, q, nv, pos, geometry, mesh });
  }

  function setFrame(f) {
    for (const it of seqs) {
      const base = f * it.nv * 3;
      const a = it.pos.array;
      for (let i = 0; i < it.nv * 3; i++) {
        const c = i % 3;
        a[i] = it.s.centre[c] + it.s.scale[c] * (it.q[base + i] / 32767);
      }
      it.pos.needsUpdate = true;
      it.geometry.computeVertexNormals();
      it.geometry.computeBoundingSphere();
    }
    counter.textContent = String(f);
    slider.value = String(f);
  }

  setFrame(0);
  // Frame the whole motion of every body, not only frame 0: a sequence's positions span
  // centre +- scale over all its frames (the quantisation box), offset by its mesh position.
  const box = new THREE.Box3();
  for (const it of seqs) {
    const c = new THREE.Vector3(...it.s.centre).add(it.mesh.position);
    const h = new THREE.Vector3(...it.s.scale);
    box.expandByPoint(c.clone().sub(h));
    box.expandByPoint(c.clone().add(h));
  }
  const centre = box.getCenter(new THREE.Vector3());
  const size = box.getSize(new THREE.Vector3());
  const camera = new THREE.PerspectiveCamera(35, host.clientWidth / host.clientHeight, 0.01, 1000);
  const dist = 1.2 * Math.max(size.x / camera.aspect, size.y) / (2 * Math.tan((camera.fov * Math.PI) / 360));
  camera.position.set(centre.x, centre.y + 0.15 * size.y, centre.z + dist + size.z);
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.copy(centre);
  controls.update();

  slider.max = String(view.nFrames - 1);
  let frame = 0;
  let playing = false;
  let last = 0;
  const dt = (1000 * view.stride) / view.fps;
  slider.addEventListener('input', () => {
    frame = Number(slider.value);
    setFrame(frame);
  });
  play.addEventListener('click', () => {
    playing = !playing;
    last = 0;
    play.textContent = playing ? 'Pause' : 'Play';
  });
  // Playback follows the clock (frames are skipped when drawing is slow).
  renderer.setAnimationLoop((t) => {
    if (playing) {
      if (last === 0) last = t;
      const steps = Math.floor((t - last) / dt);
      if (steps > 0) {
        last += steps * dt;
        frame = (frame + steps) % view.nFrames;
        setFrame(frame);
      }
    }
    renderer.render(scene, camera);
  });
  window.addEventListener('resize', () => {
    camera.aspect = host.clientWidth / host.clientHeight;
    camera.updateProjectionMatrix();
    renderer.setSize(host.clientWidth, host.clientHeight);
  });
}

if (window.SURFCAP_VIEW && window.SURFCAP_VIEW.seqs.length > 0) start(window.SURFCAP_VIEW);
