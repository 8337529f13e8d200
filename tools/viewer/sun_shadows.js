// Suns an engine draws (VOXLIGHT_light_bake "indirect" on a directional light,
// docs/light-bake-modes.md): the lightmap holds their indirect light, and this draws their
// direct light per pixel, E·cos θ / π × visibility, from a shadow map whose edges are softened
// by the sun's disk (`angularDiameter`, percentage-closer soft shadows: the penumbra's width
// from the blockers' mean depth). `voxlight view` uses it; for one's own three.js shader:
//
//   import { PUNCTUAL_GLSL } from './punctual.js';
//   import { drawnSuns, SunShadowMaps, SUN_SHADOW_GLSL } from './sun_shadows.js';
//   const shadows = new SunShadowMaps(drawnSuns(gltf), gltf.scene);
//   shadows.render(renderer, gltf.scene);               // once: the scene does not move
//   material.uniforms = { ...material.uniforms, ...shadows.uniforms };
//   // fragment shader: PUNCTUAL_GLSL, SUN_SHADOW_GLSL, then
//   //   light += drawnSunLight(worldPosition, geometricNormal, shadingNormal);
//   // the normals unit, world space, on the side the camera sees.
import * as THREE from 'three';
import { bakedLights } from './punctual.js';

export const MAX_DRAWN_SUNS = 2;

// The drawn suns of a GLTFLoader result, where its scene puts them now (punctual.js
// bakedLights), each with its `angularDiameter`.
export function drawnSuns(gltf) {
  return bakedLights(gltf, (definition, bake) => definition.type === 'directional' && bake.mode === 'indirect')
    .map((light) => ({ ...light, angularDiameter: light.bake.angularDiameter ?? 0 }))
    .slice(0, MAX_DRAWN_SUNS);
}

// One depth map a sun, an orthographic view along its light over the whole scene's bounds.
export class SunShadowMaps {
  constructor(suns, world, size = 2048) {
    this.suns = suns;
    this.size = size;
    const box = new THREE.Box3().setFromObject(world);
    const corners = [];
    for (let i = 0; i < 8; ++i)
      corners.push(new THREE.Vector3(i & 1 ? box.max.x : box.min.x, i & 2 ? box.max.y : box.min.y, i & 4 ? box.max.z : box.min.z));
    const centre = box.getCenter(new THREE.Vector3());
    const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1e-6);
    this.maps = suns.map((sun) => {
      const camera = new THREE.OrthographicCamera();
      camera.position.copy(centre).addScaledVector(sun.direction, -2 * radius);
      camera.up.set(Math.abs(sun.direction.y) < 0.9 ? 0 : 1, Math.abs(sun.direction.y) < 0.9 ? 1 : 0, 0);
      camera.lookAt(centre);
      camera.updateMatrixWorld(true);
      // The bounds' corners in the light's frame: the map is square and just holds them.
      const toLight = camera.matrixWorldInverse;
      const lo = new THREE.Vector3(Infinity, Infinity, Infinity), hi = lo.clone().negate();
      for (const c of corners) { const p = c.clone().applyMatrix4(toLight); lo.min(p); hi.max(p); }
      const half = Math.max(hi.x - lo.x, hi.y - lo.y) / 2 * 1.01;
      const mid = new THREE.Vector2((hi.x + lo.x) / 2, (hi.y + lo.y) / 2);
      camera.left = mid.x - half; camera.right = mid.x + half;
      camera.bottom = mid.y - half; camera.top = mid.y + half;
      camera.near = Math.max(-hi.z - 0.01 * radius, 1e-4);
      camera.far = -lo.z + 0.01 * radius;
      camera.updateProjectionMatrix();
      const target = new THREE.WebGLRenderTarget(size, size, { depthBuffer: true });
      target.depthTexture = new THREE.DepthTexture(size, size, THREE.FloatType);
      target.depthTexture.minFilter = target.depthTexture.magFilter = THREE.NearestFilter;
      const bias = new THREE.Matrix4().set(0.5, 0, 0, 0.5, 0, 0.5, 0, 0.5, 0, 0, 0.5, 0.5, 0, 0, 0, 1);
      const matrix = bias.multiply(camera.projectionMatrix).multiply(camera.matrixWorldInverse);
      const right = new THREE.Vector3().setFromMatrixColumn(camera.matrixWorld, 0).normalize();
      const up = new THREE.Vector3().setFromMatrixColumn(camera.matrixWorld, 1).normalize();
      return { camera, target, matrix, right, up, texel: (2 * half) / size, range: camera.far - camera.near };
    });
    const vectors = () => Array.from({ length: MAX_DRAWN_SUNS }, () => new THREE.Vector4());
    const color = vectors(), direction = vectors(), shape = vectors(), right = vectors(), up = vectors();
    const matrices = Array.from({ length: MAX_DRAWN_SUNS }, () => new THREE.Matrix4());
    this.maps.forEach((map, k) => {
      const sun = suns[k];
      color[k].set(sun.color.x, sun.color.y, sun.color.z, 0);
      direction[k].set(sun.direction.x, sun.direction.y, sun.direction.z, 0);
      shape[k].set(map.texel, map.range, Math.tan(sun.angularDiameter / 2), 0);
      right[k].set(map.right.x, map.right.y, map.right.z, 0);
      up[k].set(map.up.x, map.up.y, map.up.z, 0);
      matrices[k].copy(map.matrix);
    });
    this.uniforms = {
      drawnSunCount: { value: suns.length },
      drawnSunColor: { value: color },
      drawnSunDirection: { value: direction },
      drawnSunShape: { value: shape },  // m a texel, the depth range in m, tan of the disk's half-angle
      drawnSunRight: { value: right },  // the map's u and v axes in the world
      drawnSunUp: { value: up },
      drawnSunMatrix: { value: matrices },
      drawnSunMap0: { value: this.maps[0]?.target.depthTexture ?? null },
      drawnSunMap1: { value: this.maps[1]?.target.depthTexture ?? null },
    };
  }

  // Draws the depth maps (every surface, both sides: the bake's shadow rays meet either).
  // Each mesh draws with a plain depth material meanwhile: its own may read these maps, and a
  // map read while it is drawn into draws nothing. (`world` may be a Group, which has no
  // overrideMaterial.)
  render(renderer, world) {
    const material = new THREE.MeshBasicMaterial({ colorWrite: false, side: THREE.DoubleSide });
    const own = new Map();
    world.traverse((object) => { if (object.isMesh) { own.set(object, object.material); object.material = material; } });
    const previous = { target: renderer.getRenderTarget(), xr: renderer.xr.enabled };
    renderer.xr.enabled = false;
    for (const map of this.maps) {
      renderer.setRenderTarget(map.target);
      renderer.clear(true, true, false);
      renderer.render(world, map.camera);
    }
    renderer.setRenderTarget(previous.target);
    renderer.xr.enabled = previous.xr;
    for (const [object, mine] of own) object.material = mine;
    material.dispose();
  }
}

// Needs punctual.js PUNCTUAL_GLSL before it.
export const SUN_SHADOW_GLSL = /* glsl */ `
uniform int drawnSunCount;
uniform vec4 drawnSunColor[${MAX_DRAWN_SUNS}];
uniform vec4 drawnSunDirection[${MAX_DRAWN_SUNS}];
uniform vec4 drawnSunShape[${MAX_DRAWN_SUNS}];
uniform vec4 drawnSunRight[${MAX_DRAWN_SUNS}];
uniform vec4 drawnSunUp[${MAX_DRAWN_SUNS}];
uniform mat4 drawnSunMatrix[${MAX_DRAWN_SUNS}];
uniform highp sampler2D drawnSunMap0;
uniform highp sampler2D drawnSunMap1;

float drawnSunDepth(int k, vec2 uv) {
  // Level 0 by name: read in loops and branches, where implicit derivatives are undefined.
  return k == 0 ? textureLod(drawnSunMap0, uv, 0.0).r : textureLod(drawnSunMap1, uv, 0.0).r;
}

// A fixed spiral of n points over the unit disk (the same at every pixel: no noise).
vec2 drawnSunSpiral(int i, int n) {
  float r = sqrt((float(i) + 0.5) / float(n));
  float a = float(i) * 2.39996323;
  return r * vec2(cos(a), sin(a));
}

// How much of sun k p sees: the blockers' mean depth over the widest penumbra the disk can
// cast, then the share of the map's texels over the penumbra that lie in front of p's own
// plane (each compared with the plane's depth there, not p's: a sloped receiver does not
// shadow itself).
float drawnSunVisibility(int k, vec3 p, vec3 ng) {
  vec4 shape = drawnSunShape[k];
  float texel = shape.x, range = shape.y, tanHalf = shape.z;
  float width = texel * float(textureSize(drawnSunMap0, 0).x);  // the map's side in metres
  vec4 s = drawnSunMatrix[k] * vec4(p + ng * (1.5 * texel), 1.0);
  if (s.x <= 0.0 || s.x >= 1.0 || s.y <= 0.0 || s.y >= 1.0 || s.z >= 1.0) return 1.0;
  float depth = s.z * range;  // metres from the map's near plane
  float bias = 2.0 * texel;
  // The receiver plane's depth per metre along the map's axes (bounded where it grazes).
  float facing = max(abs(dot(ng, drawnSunDirection[k].xyz)), 0.2);
  vec2 slope = -vec2(dot(ng, drawnSunRight[k].xyz), dot(ng, drawnSunUp[k].xyz)) / (facing * sign(dot(ng, drawnSunDirection[k].xyz) + 1e-9));
  float searchRadius = max(tanHalf * depth, 1.5 * texel);
  float blockers = 0.0, blockerDepth = 0.0;
  for (int i = 0; i < 16; ++i) {
    vec2 offset = searchRadius * drawnSunSpiral(i, 16);
    float d = drawnSunDepth(k, s.xy + offset / width) * range;
    if (d < depth + dot(slope, offset) - bias) { blockers += 1.0; blockerDepth += d; }
  }
  if (blockers == 0.0) return 1.0;
  blockerDepth /= blockers;
  float radius = max(tanHalf * (depth - blockerDepth), 0.75 * texel);
  float open = 0.0;
  for (int i = 0; i < 32; ++i) {
    vec2 offset = radius * drawnSunSpiral(i, 32);
    float d = drawnSunDepth(k, s.xy + offset / width) * range;
    open += d < depth + dot(slope, offset) - bias ? 0.0 : 1.0;
  }
  return open / 32.0;
}

// Σ over the drawn suns of E·cos θ / π × visibility: what to add to the lightmap's E/π.
vec3 drawnSunLight(vec3 p, vec3 ng, vec3 ns) {
  vec3 sum = vec3(0.0);
  for (int k = 0; k < ${MAX_DRAWN_SUNS}; ++k) {
    if (k >= drawnSunCount) break;
    vec3 e = punctualIrradiance(vec4(drawnSunColor[k].rgb, 0.0), vec4(0.0), drawnSunDirection[k], vec4(0.0), p, ng, ns);
    if (e == vec3(0.0)) continue;
    sum += e * (drawnSunVisibility(k, p, ng) / 3.14159265358979);
  }
  return sum;
}
`;
