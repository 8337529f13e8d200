// The viewer page of `voxlight view`: a bake's scene.glb shown with its lightmaps.
//
// Every surface is drawn as the bake sees it: outgoing radiance = albedo × lightmap (the
// lightmap holds E/π, the README's convention) + emission, with no lights of three.js' own,
// then exposure and the sRGB curve, clamped, exactly as the bake writes image.png. The
// lightmap (MOZ_lightmap: RGBM in an 8-bit PNG, `intensity` its range) is decoded texel by
// texel and only then filtered bilinearly, so the page shows the EXR's values between texels,
// not a blend of encoded ones.
//
// ?capture (with scene, camera, mode, exposure, width, height) renders one frame at that size
// from that glTF camera and POSTs the canvas as PNG to /capture: `voxlight view --screenshot`
// and the browser test use it. ?capture=page runs the page as usual and POSTs /ready once it
// has drawn, for the browser's own screenshot of it (`--screenshot --whole-page`).
// ?material=three draws with three.js' materials instead (moz_lightmap.js, for one's own scene).
// The lights the bake left to the engine are drawn as an engine draws them, added to the
// lightmap: a "shadowmask" light as its unshadowed direct light times its channel of the
// material's shadowmask (shadowmask.js); an "indirect" sun with a shadow map softened by its
// disk (sun_shadows.js); an "indirect" point or spot light with a cube map of distances
// (lamp_shadows.js). Past two suns and two lamps the page says what it leaves out.
// When scene.glb has an irradiance volume (VOXLIGHT_irradiance_volume, irradiance_volume.js),
// objects the bake did not see are lit from it: ?sphere=x,y,z,r[,albedo | ,r,g,b] (world metres,
// repeatable; captures show it too), a sphere added with the panel's button or N and dragged
// with the mouse, and a .glb/.gltf dropped on the page.
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { PointerLockControls } from 'three/addons/controls/PointerLockControls.js';
import { VRButton } from 'three/addons/webxr/VRButton.js';
import { applyMozLightmaps } from './moz_lightmap.js';
import { shadowmaskLights, shadowmaskUniforms, SHADOWMASK_GLSL } from './shadowmask.js';
import { drawnSuns, SunShadowMaps, SUN_SHADOW_GLSL } from './sun_shadows.js';
import { drawnLamps, LampShadowMaps, LAMP_SHADOW_GLSL } from './lamp_shadows.js';
import { PUNCTUAL_GLSL } from './punctual.js';
import { loadIrradianceVolume } from './irradiance_volume.js';
import { dynamicObjects, parseSpheres, volumeSphere } from './moving_objects.js';

const params = new URLSearchParams(location.search);
const capturing = params.get('capture') === '';         // the canvas alone, posted to /capture
const capturingPage = params.get('capture') === 'page';  // the whole page: /ready once drawn
const MODES = { lit: 0, lightmap: 1, albedo: 2 };
const UNLIT_LEVEL = 0.1;  // what a surface the bake did not light shows: albedo × this, in lit mode
// (lightmap/lightmap_image.h kUnlitLight, which image_lightmapped.exr uses: test_view holds the two together)

const report = window.voxlightReport;  // index.html's, which also sees a module that fails to load

// ---- the surface shader -------------------------------------------------------------------

const vertexShader = /* glsl */ `
precision highp float;
uniform mat4 modelViewMatrix;
uniform mat4 projectionMatrix;
uniform mat3 baseMapTransform;
uniform mat3 emissiveMapTransform;
in vec3 position;
#ifdef USE_INSTANCING
in mat4 instanceMatrix;
#endif
#ifdef HAS_UV0
in vec2 uv;
#endif
#ifdef HAS_UV1
in vec2 uv1;
#endif
#ifdef HAS_COLOR
in COLOR_TYPE color;
out vec4 vColor;
#endif
out vec2 vBaseUv;
out vec2 vEmissiveUv;
out vec2 vLightmapUv;
#if defined(HAS_SHADOWMASK) || defined(HAS_DRAWN_SUNS) || defined(HAS_DRAWN_LAMPS)
uniform mat4 modelMatrix;
#ifdef HAS_NORMAL
in vec3 normal;
#endif
out vec3 vWorldPosition;
out vec3 vWorldNormal;
#endif

vec2 channel(int which) {
  vec2 t = vec2(0.0);
#ifdef HAS_UV0
  if (which == 0) t = uv;
#endif
#ifdef HAS_UV1
  if (which == 1) t = uv1;
#endif
  return t;
}

void main() {
  vBaseUv = (baseMapTransform * vec3(channel(BASE_CHANNEL), 1.0)).xy;
  vEmissiveUv = (emissiveMapTransform * vec3(channel(EMISSIVE_CHANNEL), 1.0)).xy;
  vLightmapUv = channel(LIGHTMAP_CHANNEL);
#ifdef HAS_COLOR
  vColor = vec4(1.0);
  vColor.COLOR_SWIZZLE = color;
#endif
  vec4 p = vec4(position, 1.0);
#ifdef USE_INSTANCING
  p = instanceMatrix * p;
#endif
  gl_Position = projectionMatrix * modelViewMatrix * p;
#if defined(HAS_SHADOWMASK) || defined(HAS_DRAWN_SUNS) || defined(HAS_DRAWN_LAMPS)
  mat4 toWorld = modelMatrix;
#ifdef USE_INSTANCING
  toWorld = modelMatrix * instanceMatrix;
#endif
  vWorldPosition = (toWorld * vec4(position, 1.0)).xyz;
#ifdef HAS_NORMAL
  vWorldNormal = transpose(inverse(mat3(toWorld))) * normal;
#else
  vWorldNormal = vec3(0.0);  // flat: the fragment takes its geometric normal
#endif
#endif
}
`;

const fragmentShader = /* glsl */ `
precision highp float;
precision highp int;
uniform vec4 baseColorFactor;
uniform sampler2D baseColorMap;
uniform vec3 emissiveFactor;
uniform sampler2D emissiveMap;
uniform sampler2D lightMap;
uniform float lightMapRange;
uniform float alphaCutoff;
uniform int mode;
uniform float exposure;
in vec2 vBaseUv;
in vec2 vEmissiveUv;
in vec2 vLightmapUv;
#ifdef HAS_COLOR
in vec4 vColor;
#endif
#if defined(HAS_SHADOWMASK) || defined(HAS_DRAWN_SUNS) || defined(HAS_DRAWN_LAMPS)
uniform vec3 cameraPosition;
in vec3 vWorldPosition;
in vec3 vWorldNormal;
${PUNCTUAL_GLSL}
#endif
#ifdef HAS_SHADOWMASK
${SHADOWMASK_GLSL}
#endif
#ifdef HAS_DRAWN_LAMPS
${LAMP_SHADOW_GLSL}
#endif
#ifdef HAS_DRAWN_SUNS
${SUN_SHADOW_GLSL}
#endif
out vec4 fragColor;

vec3 lightmapTexel(ivec2 p, ivec2 size) {
  vec4 t = texelFetch(lightMap, clamp(p, ivec2(0), size - 1), 0);
  return t.rgb * t.a * lightMapRange;
}

// Bilinear between decoded texels, texel centres at (i + 0.5) / size as the bake samples them.
vec3 lightmapAt(vec2 uv) {
  ivec2 size = textureSize(lightMap, 0);
  vec2 p = uv * vec2(size) - 0.5;
  vec2 cell = floor(p);
  vec2 f = p - cell;
  ivec2 i = ivec2(cell);
  vec3 bottom = mix(lightmapTexel(i, size), lightmapTexel(i + ivec2(1, 0), size), f.x);
  vec3 top = mix(lightmapTexel(i + ivec2(0, 1), size), lightmapTexel(i + ivec2(1, 1), size), f.x);
  return mix(bottom, top, f.y);
}

vec3 toSrgb(vec3 c) {
  c = clamp(c, 0.0, 1.0);
  return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}

void main() {
  vec4 albedo = baseColorFactor;
#ifdef HAS_BASE_MAP
  albedo *= texture(baseColorMap, vBaseUv);  // an sRGB texture: sampled in linear light
#endif
#ifdef HAS_COLOR
  albedo *= vColor;
#endif
#ifdef ALPHA_MASK
  if (albedo.a < alphaCutoff) discard;
#endif
  vec3 emission = emissiveFactor;
#ifdef HAS_EMISSIVE_MAP
  emission *= texture(emissiveMap, vEmissiveUv).rgb;
#endif
#ifdef HAS_LIGHTMAP
  vec3 light = lightmapAt(vLightmapUv);
#if defined(HAS_SHADOWMASK) || defined(HAS_DRAWN_SUNS) || defined(HAS_DRAWN_LAMPS)
  // The side the camera sees, as the bake's lightmap-lit image takes it.
  vec3 ng = normalize(cross(dFdx(vWorldPosition), dFdy(vWorldPosition)));
  if (dot(ng, cameraPosition - vWorldPosition) < 0.0) ng = -ng;
  vec3 ns = dot(vWorldNormal, vWorldNormal) > 0.0 ? normalize(vWorldNormal) * (gl_FrontFacing ? 1.0 : -1.0) : ng;
#endif
#ifdef HAS_SHADOWMASK
  light += shadowmaskLight(vWorldPosition, ng, ns, vLightmapUv);
#endif
#ifdef HAS_DRAWN_SUNS
  light += drawnSunLight(vWorldPosition, ng, ns);
#endif
#ifdef HAS_DRAWN_LAMPS
  light += drawnLampLight(vWorldPosition, ng, ns);
#endif
#else
  vec3 light = vec3(${UNLIT_LEVEL.toFixed(3)});
#endif
  vec3 radiance = mode == 0 ? albedo.rgb * light + emission : mode == 1 ? light : albedo.rgb;
#ifdef ALPHA_BLEND
  float alpha = albedo.a;
#else
  float alpha = 1.0;
#endif
  fragColor = vec4(toSrgb(radiance * exposure), alpha);
}
`;

const identity3 = new THREE.Matrix3();

function textureMatrix(texture) {
  if (!texture) return identity3;
  texture.updateMatrix();
  return texture.matrix;
}

// One material per (glTF material, attributes the geometry has): the shader reads only what exists.
function bakedMaterial(source, geometry, lightmap, shared, instanced, maskLights, engine) {
  const color = geometry.getAttribute('color');
  const defines = {
    BASE_CHANNEL: source.map ? source.map.channel : 0,
    EMISSIVE_CHANNEL: source.emissiveMap ? source.emissiveMap.channel : 0,
    LIGHTMAP_CHANNEL: lightmap ? lightmap.channel : 1,
  };
  if (geometry.getAttribute('uv')) defines.HAS_UV0 = '';
  if (geometry.getAttribute('uv1')) defines.HAS_UV1 = '';
  if (source.vertexColors && color) {
    defines.HAS_COLOR = '';
    defines.COLOR_TYPE = color.itemSize === 4 ? 'vec4' : 'vec3';
    defines.COLOR_SWIZZLE = color.itemSize === 4 ? 'rgba' : 'rgb';
  }
  if (source.map) defines.HAS_BASE_MAP = '';
  if (source.emissiveMap) defines.HAS_EMISSIVE_MAP = '';
  if (lightmap) defines.HAS_LIGHTMAP = '';
  const masked = lightmap && lightmap.shadowmask && maskLights.length > 0;
  if (masked) defines.HAS_SHADOWMASK = '';
  const sunlit = lightmap && engine && engine.suns.suns.length > 0;
  if (sunlit) defines.HAS_DRAWN_SUNS = '';
  const lamplit = lightmap && engine && engine.lamps.lamps.length > 0;
  if (lamplit) defines.HAS_DRAWN_LAMPS = '';
  if (geometry.getAttribute('normal')) defines.HAS_NORMAL = '';
  if (source.alphaTest > 0) defines.ALPHA_MASK = '';
  if (source.transparent) defines.ALPHA_BLEND = '';
  if (instanced) defines.USE_INSTANCING = '';
  const emissive = source.emissive ? source.emissive.clone().multiplyScalar(source.emissiveIntensity ?? 1) : new THREE.Color(0, 0, 0);
  return new THREE.RawShaderMaterial({
    name: source.name,
    glslVersion: THREE.GLSL3,
    vertexShader,
    fragmentShader,
    defines,
    side: source.side,
    transparent: source.transparent,
    depthWrite: source.depthWrite,
    uniforms: {
      baseColorFactor: { value: new THREE.Vector4(source.color.r, source.color.g, source.color.b, source.opacity) },
      baseColorMap: { value: source.map || null },
      baseMapTransform: { value: textureMatrix(source.map) },
      emissiveFactor: { value: emissive },
      emissiveMap: { value: source.emissiveMap || null },
      emissiveMapTransform: { value: textureMatrix(source.emissiveMap) },
      lightMap: { value: lightmap ? lightmap.texture : null },
      lightMapRange: { value: lightmap ? lightmap.range : 0 },
      alphaCutoff: { value: source.alphaTest },
      mode: shared.mode,
      exposure: shared.exposure,
      ...(masked ? shadowmaskUniforms(maskLights, lightmap.shadowmask) : {}),
      ...(sunlit ? engine.suns.uniforms : {}),
      ...(lamplit ? engine.lamps.uniforms : {}),
    },
  });
}

// A texture of the glTF file as data: texel values as stored, filtered in the shader.
function dataTexture(parser, index, cache) {
  if (!cache.has(index)) {
    cache.set(index, parser.getDependency('texture', index).then((texture) => {
      const data = texture.clone();  // the same image may serve as a colour map elsewhere
      data.colorSpace = THREE.NoColorSpace;
      data.flipY = false;
      data.generateMipmaps = false;
      data.minFilter = data.magFilter = THREE.NearestFilter;  // filtered in the shader, after decoding
      data.needsUpdate = true;
      return data;
    }));
  }
  return cache.get(index);
}

// MOZ_lightmap of the glTF material behind a three.js material: its texture, decoded as data;
// with its VOXLIGHT_shadowmask's texture, when it has one.
async function lightmapOf(parser, material, cache) {
  const association = parser.associations.get(material);
  if (!association || association.materials === undefined) return null;
  const definition = parser.json.materials[association.materials];
  const extension = definition.extensions && definition.extensions.MOZ_lightmap;
  if (!extension) return null;
  const texture = await dataTexture(parser, extension.index, cache);
  const mask = definition.extensions.VOXLIGHT_shadowmask;
  const shadowmask = mask ? await dataTexture(parser, mask.index, cache) : null;
  return { texture, range: extension.intensity ?? 1, channel: extension.texCoord ?? 0, shadowmask };
}

async function applyBakedMaterials(gltf, shared, engine) {
  const meshes = [];
  gltf.scene.traverse((object) => { if (object.isMesh) meshes.push(object); });
  const textures = new Map();
  const made = new Map();
  const maskLights = shadowmaskLights(gltf);
  let unlit = 0;
  for (const mesh of meshes) {
    const sources = Array.isArray(mesh.material) ? mesh.material : [mesh.material];
    const replaced = [];
    for (const source of sources) {
      const lightmap = await lightmapOf(gltf.parser, source, textures);
      const emits = source.emissive && source.emissive.r + source.emissive.g + source.emissive.b > 0;
      if (!lightmap && !emits) ++unlit;  // an emitter shows its emission, lightmap or not
      const geometry = mesh.geometry;
      const key = [source.uuid, !!geometry.getAttribute('uv'), !!geometry.getAttribute('uv1'), !!geometry.getAttribute('normal'),
                   geometry.getAttribute('color') ? geometry.getAttribute('color').itemSize : 0, !!mesh.isInstancedMesh].join();
      if (!made.has(key))
        made.set(key, bakedMaterial(source, geometry, lightmap, shared, !!mesh.isInstancedMesh, maskLights, engine));
      replaced.push(made.get(key));
    }
    mesh.material = Array.isArray(mesh.material) ? replaced : replaced[0];
  }
  return { meshes: meshes.length, unlit };
}

// ---- cameras ------------------------------------------------------------------------------

function glTFCameras(gltf) {
  gltf.scene.updateMatrixWorld(true);
  return gltf.cameras.map((camera, i) => ({ name: camera.name || `camera ${i}`, camera }));
}

// Puts the view camera where a glTF camera is, with its vertical field of view.
function jumpTo(view, source, aspect) {
  source.updateMatrixWorld(true);
  source.matrixWorld.decompose(view.position, view.quaternion, new THREE.Vector3());
  if (source.isPerspectiveCamera) view.fov = source.fov;
  view.aspect = aspect;
  view.updateProjectionMatrix();
}

function frameBox(view, box, aspect) {
  const size = box.getSize(new THREE.Vector3());
  const centre = box.getCenter(new THREE.Vector3());
  const radius = Math.max(size.length() / 2, 1e-6);
  view.fov = 50;
  view.aspect = aspect;
  view.position.copy(centre).add(new THREE.Vector3(0.6, 0.5, 1).normalize().multiplyScalar(radius * 2.2));
  view.lookAt(centre);
  view.updateProjectionMatrix();
}

// ---- the page -----------------------------------------------------------------------------

async function fetchJson(url) {
  const response = await fetch(url);
  if (!response.ok) throw new Error(`${url}: ${response.status} ${response.statusText}`);
  return response.json();
}

function sceneUrl(scene, file) {
  return './scene/' + (scene ? scene.split('/').map(encodeURIComponent).join('/') + '/' : '') + file;
}

async function main() {
  if (capturing) document.body.classList.add('capture');
  const { scenes } = await fetchJson('./scenes.json');
  const scene = params.get('scene') ?? scenes[0];
  if (!scenes.includes(scene)) throw new Error(`no scene "${scene}" here; there are: ${scenes.join(', ')}`);

  const width = capturing ? Number(params.get('width')) : window.innerWidth;
  const height = capturing ? Number(params.get('height')) : window.innerHeight;
  const renderer = new THREE.WebGLRenderer({ antialias: !capturing, preserveDrawingBuffer: capturing });
  renderer.setPixelRatio(capturing ? 1 : window.devicePixelRatio);
  renderer.setSize(width, height);
  renderer.outputColorSpace = THREE.LinearSRGBColorSpace;  // the shader writes sRGB itself
  renderer.toneMapping = THREE.NoToneMapping;
  renderer.setClearColor(0x000000);
  document.body.appendChild(renderer.domElement);

  const shared = {
    mode: { value: MODES[params.get('mode') ?? 'lit'] ?? 0 },
    exposure: { value: Math.pow(2, Number(params.get('exposure') ?? 0)) },
  };
  const gltf = await new GLTFLoader().loadAsync(sceneUrl(scene, 'scene.glb'));
  const volume = await loadIrradianceVolume(gltf).catch((error) => { report(error.message); return null; });
  // ?material=three: three.js' own materials through moz_lightmap.js, the README's recipe (the
  // show and exposure controls do not apply to them).
  const threeMaterials = params.get('material') === 'three';
  if (threeMaterials) renderer.outputColorSpace = THREE.SRGBColorSpace;
  // Lights whose direct light the bake left to the engine: a shadow map each, drawn once.
  const engine = threeMaterials ? null
    : { suns: new SunShadowMaps(drawnSuns(gltf), gltf.scene), lamps: new LampShadowMaps(drawnLamps(gltf)) };
  const counts = threeMaterials ? { meshes: await applyMozLightmaps(gltf), unlit: 0 }
                                : await applyBakedMaterials(gltf, shared, engine);
  const world = gltf.scene;
  if (engine) {
    engine.suns.render(renderer, world);
    engine.lamps.render(renderer, world);
  }
  // Lights whose direct light the bake left to the engine's shadow maps (VOXLIGHT_light_bake
  // "indirect", docs/light-bake-modes.md) past what this page draws (two suns, two lamps):
  // say what is missing.
  const engineDrawn = (gltf.parser.json.extensions?.KHR_lights_punctual?.lights ?? [])
    .map((light, i) => ({ light, name: light.name || `light ${i}` }))
    .filter(({ light }) => light.extensions?.VOXLIGHT_light_bake?.mode === 'indirect');
  const drawnCount = engine ? engine.suns.suns.length + engine.lamps.lamps.length : 0;
  if (engineDrawn.length > drawnCount)
    report(`the lightmaps hold only the indirect light of ${engineDrawn.map(({ name }) => name).join(', ')} ` +
           `(light-bake indirect); this viewer draws the direct light of ${drawnCount} of them ` +
           '(two suns and two point or spot lights at most): image_lightmapped.exr shows all');
  // three.js' own materials (moz_lightmap.js) show the lightmaps alone.
  const maskedCount = (gltf.parser.json.extensions?.KHR_lights_punctual?.lights ?? [])
    .filter((light) => light.extensions?.VOXLIGHT_light_bake?.mode === 'shadowmask').length;
  if (threeMaterials && maskedCount > 0)
    report(`three.js materials (moz_lightmap.js) do not draw the ${maskedCount} shadowmask light(s) the lightmaps ` +
           'leave out: the page without ?material=three does');
  // A bake under a uniform sky writes its radiance into the scene's extras (glTF has no sky):
  // lit, the background is that sky, with the exposure and the sRGB curve the shader applies.
  const sky = world.userData?.voxlight?.sky;
  const skyBackground = () => {
    if (!sky || shared.mode.value !== 0 || threeMaterials) return renderer.setClearColor(0x000000);
    const srgb = sky.map((c) => {
      const v = Math.min(Math.max(c * shared.exposure.value, 0), 1);
      return v <= 0.0031308 ? v * 12.92 : 1.055 * Math.pow(v, 1 / 2.4) - 0.055;
    });
    // Linear working space and linear output: the encoded bytes pass through as the shader's do.
    renderer.setClearColor(new THREE.Color().setRGB(srgb[0], srgb[1], srgb[2], THREE.LinearSRGBColorSpace));
  };
  const cameras = glTFCameras(gltf);
  const box = new THREE.Box3().setFromObject(world);
  const size = box.getSize(new THREE.Vector3()).length() || 1;

  const view = new THREE.PerspectiveCamera(50, width / height, size * 1e-4, size * 20);
  const chosen = Number(params.get('camera') ?? 0);
  if (cameras[chosen]) jumpTo(view, cameras[chosen].camera, width / height);
  else frameBox(view, box, width / height);

  // Spheres of ?sphere, lit by the irradiance volume (after the box: they do not frame the view).
  let spheres = [];
  try {
    spheres = parseSpheres(params.getAll('sphere'));
  } catch (error) {
    report(error.message);
  }
  if (spheres.length > 0 && !volume) report('?sphere: no irradiance volume in this bake to light it');
  const urlSpheres = volume ? spheres.map((s) => volumeSphere(volume, shared, s.centre, s.radius, s.albedo)) : [];

  if (capturing) {
    for (const sphere of urlSpheres) world.add(sphere);
    if (chosen >= 0 && params.has('camera') && !cameras[chosen]) throw new Error(`the scene has no camera ${chosen} (it has ${cameras.length})`);
    skyBackground();
    renderer.render(world, view);
    const blob = await new Promise((resolve) => renderer.domElement.toBlob(resolve, 'image/png'));
    await fetch('/capture', { method: 'POST', body: blob });
    return;
  }

  // Scenes, cameras, modes, exposure.
  const sceneSelect = document.getElementById('scene');
  for (const name of scenes) sceneSelect.add(new Option(name || '(this folder)', name, false, name === scene));
  sceneSelect.onchange = () => { params.set('scene', sceneSelect.value); params.delete('camera'); location.search = params; };
  const cameraSelect = document.getElementById('camera');
  cameraSelect.add(new Option('whole scene', '-1', false, !cameras[chosen]));
  cameras.forEach((c, i) => cameraSelect.add(new Option(c.name, String(i), false, i === chosen)));
  for (const button of document.querySelectorAll('[data-mode]')) {
    button.classList.toggle('on', MODES[button.dataset.mode] === shared.mode.value);
    button.onclick = () => {
      shared.mode.value = MODES[button.dataset.mode];
      for (const b of document.querySelectorAll('[data-mode]')) b.classList.toggle('on', b === button);
    };
  }
  const exposure = document.getElementById('exposure');
  exposure.value = params.get('exposure') ?? 0;
  exposure.oninput = () => {
    shared.exposure.value = Math.pow(2, Number(exposure.value));
    document.getElementById('exposureValue').textContent = exposure.value;
  };
  exposure.oninput();

  // Orbit about a point ahead of the camera; walk with the mouse captured (WASD, Q/E down/up).
  // (OrbitControls turns the camera to its target, the origin, when made: the view is placed again.)
  const orbit = new OrbitControls(view, renderer.domElement);
  const walk = new PointerLockControls(view, renderer.domElement);
  const resetOrbitTarget = () => {
    const ahead = new THREE.Vector3(0, 0, -1).applyQuaternion(view.quaternion);
    const distance = Math.max(box.getCenter(new THREE.Vector3()).sub(view.position).dot(ahead), size * 0.05);
    orbit.target.copy(view.position).addScaledVector(ahead, distance);
    orbit.update();
  };
  const place = (i) => {
    if (cameras[i]) jumpTo(view, cameras[i].camera, view.aspect);
    else frameBox(view, box, view.aspect);
    resetOrbitTarget();
  };
  place(chosen);
  cameraSelect.onchange = () => place(Number(cameraSelect.value));
  let walking = false;
  const setWalking = (on) => {
    walking = on;
    orbit.enabled = !on;
    document.getElementById('walk').classList.toggle('on', on);
    document.getElementById('orbit').classList.toggle('on', !on);
    if (!on) resetOrbitTarget();
  };
  document.getElementById('walk').onclick = () => { setWalking(true); walk.lock(); };
  document.getElementById('orbit').onclick = () => { walk.unlock(); setWalking(false); };
  renderer.domElement.addEventListener('click', () => { if (walking && !walk.isLocked) walk.lock(); });
  const keys = new Set();
  addEventListener('keydown', (e) => keys.add(e.code));
  addEventListener('keyup', (e) => keys.delete(e.code));

  const bake = await fetchJson(sceneUrl(scene, 'bake.json')).catch(() => null);
  document.getElementById('info').textContent = [
    `${counts.meshes} meshes` + (counts.unlit ? `, ${counts.unlit} primitives without a lightmap (shown at ${UNLIT_LEVEL} × albedo)` : ''),
    bake ? `baked in ${Number(bake.total_seconds).toFixed(2)} s, voxel size ${Number(bake.voxel_size).toPrecision(3)}` : '',
    volume ? `irradiance volume: ${volume.counts.join(' × ')} probes, ` +
             `spacing ${volume.spacing.toArray().map((d) => d.toPrecision(3)).join(' × ')} m`
           : 'no irradiance volume in this bake',
    'walk: click, then WASD, Q/E, Shift; Esc',
    volume ? 'sphere: add (N), drag (Shift: nearer/farther), Delete; drop a .glb/.gltf to light it here' : '',
  ].filter(Boolean).join('\n');

  // Objects lit by the irradiance volume: the panel's spheres, dragged; a dropped glTF.
  const dynamic = volume && dynamicObjects({ volume, shared, world, view, canvas: renderer.domElement, orbit,
                                             isWalking: () => walking, size });
  if (dynamic) {
    for (const sphere of urlSpheres) dynamic.group.add(sphere);
    document.getElementById('volume').hidden = false;
    document.getElementById('addSphere').onclick = dynamic.addSphere;
    document.getElementById('clearObjects').onclick = dynamic.clear;
    addEventListener('keydown', (e) => {
      if (e.target.tagName === 'INPUT' || e.target.tagName === 'SELECT' || e.repeat) return;
      if (e.code === 'KeyN') dynamic.addSphere();
      if (e.code === 'Delete' || e.code === 'Backspace') dynamic.remove();
    });
  }
  addEventListener('dragover', (e) => e.preventDefault());
  addEventListener('drop', (e) => {
    e.preventDefault();
    if (!dynamic) return report('no irradiance volume in this bake to light a dropped model with');
    dynamic.addModel([...e.dataTransfer.files])
      .then((note) => { if (note) document.getElementById('info').textContent += '\n' + note; })
      .catch((error) => report(error.message || String(error)));
  });

  renderer.xr.enabled = true;
  document.body.appendChild(VRButton.createButton(renderer));
  addEventListener('resize', () => {
    view.aspect = innerWidth / innerHeight;
    view.updateProjectionMatrix();
    renderer.setSize(innerWidth, innerHeight);
  });

  const timer = new THREE.Timer();
  let frames = 0;
  renderer.setAnimationLoop(() => {
    timer.update();
    const dt = Math.min(timer.getDelta(), 0.1);
    dynamic?.update(dt);
    if (walking && walk.isLocked) {
      const speed = size * 0.1 * (keys.has('ShiftLeft') || keys.has('ShiftRight') ? 4 : 1) * dt;
      const axis = (plus, minus) => (keys.has(plus) ? 1 : 0) - (keys.has(minus) ? 1 : 0);
      walk.moveForward(speed * (axis('KeyW', 'KeyS') + axis('ArrowUp', 'ArrowDown')));
      walk.moveRight(speed * (axis('KeyD', 'KeyA') + axis('ArrowRight', 'ArrowLeft')));
      view.position.y += speed * axis('KeyE', 'KeyQ');
    }
    skyBackground();
    renderer.render(world, view);
    if (capturingPage && ++frames === 2) fetch('/ready', { method: 'POST' });
  });
}

main().catch((error) => report(error.stack || String(error)));
