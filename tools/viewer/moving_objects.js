// What moves through a baked scene in `voxlight view`: spheres and dropped glTF models, drawn
// diffuse and lit by the scene's irradiance volume (irradiance_volume.js). The page places
// them from ?sphere, the panel's button or N, and a file dropped on it; they are dragged with
// the mouse (Shift: nearer or farther) and removed with Delete.
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';

// ?sphere values: x,y,z,r then nothing (albedo 0.8), one grey albedo, or an RGB one (linear).
export function parseSpheres(values) {
  return values.map((value) => {
    const n = value.split(',').map(Number);
    if (![4, 5, 7].includes(n.length) || n.some((v) => !Number.isFinite(v)) || n[3] <= 0)
      throw new Error(`?sphere=${value}: want x,y,z,r (world metres, r > 0), optionally ,albedo or ,r,g,b`);
    const albedo = n.length === 4 ? [0.8, 0.8, 0.8] : n.length === 5 ? [n[4], n[4], n[4]] : n.slice(4);
    return { centre: new THREE.Vector3(n[0], n[1], n[2]), radius: n[3], albedo };
  });
}

export function volumeSphere(volume, shared, centre, radius, albedo = [0.8, 0.8, 0.8]) {
  const material = volume.material({ name: 'sphere', color: new THREE.Color(...albedo) }, shared);
  const sphere = new THREE.Mesh(new THREE.SphereGeometry(radius, 128, 64), material);
  sphere.name = 'sphere';
  sphere.position.copy(centre);
  return sphere;
}

// Every mesh of a loaded model drawn diffuse, lit by the volume: one material per source.
function lightFromVolume(root, volume, shared) {
  const made = new Map();
  const lit = (source) => {
    if (!made.has(source)) made.set(source, volume.material(source, shared));
    return made.get(source);
  };
  root.traverse((object) => {
    if (object.isMesh) object.material = Array.isArray(object.material) ? object.material.map(lit) : lit(object.material);
  });
}

// The page's dynamic objects: added ahead of the camera, dragged in the plane facing it (Shift:
// nearer or farther), Delete removes the one last touched; a dropped glTF is lit and placed too.
export function dynamicObjects({ volume, shared, world, view, canvas, orbit, isWalking, size }) {
  const group = new THREE.Group();
  group.name = 'lit by the irradiance volume';
  world.add(group);
  const mixers = [];
  const raycaster = new THREE.Raycaster();
  let selected = null;
  let drag = null;

  // Ahead of the camera, short of the first baked surface on the way.
  const placeAhead = (object, radius) => {
    const ahead = new THREE.Vector3(0, 0, -1).applyQuaternion(view.quaternion);
    let distance = isWalking() ? size * 0.2 : orbit.target.distanceTo(view.position);
    raycaster.set(view.position, ahead);
    const hit = raycaster.intersectObjects(world.children.filter((child) => child !== group), true)[0];
    if (hit) distance = Math.min(distance, hit.distance - 1.5 * radius);
    distance = Math.max(distance, 2 * radius + view.near);
    object.position.copy(view.position).addScaledVector(ahead, distance);
    group.add(object);
    selected = object;
  };
  const addSphere = () => {
    const radius = size * 0.05;
    placeAhead(volumeSphere(volume, shared, new THREE.Vector3(), radius), radius);
  };
  const remove = () => {
    if (!selected) return;
    group.remove(selected);
    selected.traverse((object) => {
      if (!object.isMesh) return;
      object.geometry.dispose();
      for (const material of [object.material].flat()) material.dispose();
    });
    selected = group.children[group.children.length - 1] ?? null;
  };
  const clear = () => { while (group.children.length) { selected = group.children[0]; remove(); } };

  // A .glb, or a .gltf with its files dropped together: its size kept unless it would dwarf the scene.
  const addModel = async (files) => {
    const file = files.find((f) => /\.(glb|gltf)$/i.test(f.name));
    if (!file) throw new Error('drop a .glb, or a .gltf together with its .bin and images');
    const urls = new Map(files.map((f) => [f.name, URL.createObjectURL(f)]));
    const manager = new THREE.LoadingManager();
    manager.setURLModifier((url) => urls.get(decodeURIComponent(url.split('/').pop())) ?? url);
    try {
      const model = await new GLTFLoader(manager).parseAsync(await file.arrayBuffer(), '');
      lightFromVolume(model.scene, volume, shared);
      const box = new THREE.Box3().setFromObject(model.scene);
      const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1e-6);
      const scale = Math.min(1, (size * 0.25) / radius);
      const holder = new THREE.Group();
      holder.name = file.name;
      holder.add(model.scene);
      model.scene.scale.multiplyScalar(scale);
      model.scene.position.sub(box.getCenter(new THREE.Vector3())).multiplyScalar(scale);
      placeAhead(holder, radius * scale);
      if (model.animations.length) {
        const mixer = new THREE.AnimationMixer(model.scene);
        for (const clip of model.animations) mixer.clipAction(clip).play();
        mixers.push(mixer);
      }
      return scale < 1 ? `${file.name}: scaled by ${scale.toPrecision(3)} to fit the scene` : '';
    } finally {
      for (const url of urls.values()) URL.revokeObjectURL(url);
    }
  };

  const pointer = (e) => {
    const rect = canvas.getBoundingClientRect();
    return new THREE.Vector2(((e.clientX - rect.left) / rect.width) * 2 - 1, -((e.clientY - rect.top) / rect.height) * 2 + 1);
  };
  const rootOf = (object) => { while (object.parent !== group) object = object.parent; return object; };
  // Capture phase: the orbit controls, listening on the same canvas, do not see a grab.
  canvas.addEventListener('pointerdown', (e) => {
    if (e.button !== 0 || isWalking() || group.children.length === 0) return;
    raycaster.setFromCamera(pointer(e), view);
    const hit = raycaster.intersectObject(group, true)[0];
    if (!hit) return;
    e.stopImmediatePropagation();
    selected = rootOf(hit.object);
    const facing = view.getWorldDirection(new THREE.Vector3());
    drag = { facing, point: hit.point.clone(), offset: selected.position.clone().sub(hit.point), y: e.clientY };
    canvas.setPointerCapture(e.pointerId);
    canvas.style.cursor = 'grabbing';
  }, { capture: true });
  canvas.addEventListener('pointermove', (e) => {
    if (!drag) {
      if (group.children.length === 0 || isWalking() || e.buttons) return;
      raycaster.setFromCamera(pointer(e), view);
      canvas.style.cursor = raycaster.intersectObject(group, true).length ? 'grab' : '';
      return;
    }
    if (e.shiftKey) {  // up: farther
      const distance = drag.point.distanceTo(view.position);
      drag.point.addScaledVector(drag.facing, (drag.y - e.clientY) * distance * 0.003);
    } else {
      raycaster.setFromCamera(pointer(e), view);
      const plane = new THREE.Plane().setFromNormalAndCoplanarPoint(drag.facing, drag.point);
      raycaster.ray.intersectPlane(plane, drag.point);
    }
    drag.y = e.clientY;
    selected.position.copy(drag.point).add(drag.offset);
  });
  const release = (e) => {
    if (!drag) return;
    drag = null;
    canvas.releasePointerCapture(e.pointerId);
    canvas.style.cursor = 'grab';
  };
  canvas.addEventListener('pointerup', release);
  canvas.addEventListener('pointercancel', release);

  return { group, addSphere, addModel, remove, clear, update: (dt) => mixers.forEach((m) => m.update(dt)) };
}
