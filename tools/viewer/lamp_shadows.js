// Point and spot lights an engine draws (VOXLIGHT_light_bake "indirect",
// docs/light-bake-modes.md): the lightmap holds their indirect light, and this draws their
// direct light per pixel, E·cos θ / π × visibility (glTF's falloff, range window and spot
// cone), the visibility from a cube map of the distance to the nearest surface around the
// light. A point light has no size, so its shadows are hard, as the bake's one shadow ray a
// read makes them. `voxlight view` uses it; for one's own three.js shader:
//
//   import { PUNCTUAL_GLSL } from './punctual.js';
//   import { drawnLamps, LampShadowMaps, LAMP_SHADOW_GLSL } from './lamp_shadows.js';
//   const shadows = new LampShadowMaps(drawnLamps(gltf));
//   shadows.render(renderer, gltf.scene);               // once: the scene does not move
//   material.uniforms = { ...material.uniforms, ...shadows.uniforms };
//   // fragment shader: PUNCTUAL_GLSL, LAMP_SHADOW_GLSL, then
//   //   light += drawnLampLight(worldPosition, geometricNormal, shadingNormal);
import * as THREE from 'three';
import { bakedLights, packLights } from './punctual.js';

export const MAX_DRAWN_LAMPS = 2;

// The drawn point and spot lights of a GLTFLoader result, where its scene puts them now.
export function drawnLamps(gltf) {
  return bakedLights(gltf, (definition, bake) => definition.type !== 'directional' && bake.mode === 'indirect')
    .slice(0, MAX_DRAWN_LAMPS);
}

// Draws 1 / distance to the light (0 where nothing is: the cleared value), every surface both sides.
const distanceMaterial = (position) => new THREE.ShaderMaterial({
  side: THREE.DoubleSide,
  uniforms: { lampPosition: { value: position } },
  vertexShader: /* glsl */ `
    varying vec3 vWorld;
    void main() {
      vec4 p = vec4(position, 1.0);
    #ifdef USE_INSTANCING
      p = instanceMatrix * p;
    #endif
      vec4 world = modelMatrix * p;
      vWorld = world.xyz;
      gl_Position = projectionMatrix * viewMatrix * world;
    }`,
  fragmentShader: /* glsl */ `
    uniform vec3 lampPosition;
    varying vec3 vWorld;
    void main() { gl_FragColor = vec4(1.0 / max(distance(vWorld, lampPosition), 1e-6)); }`,
});

export class LampShadowMaps {
  constructor(lamps, size = 512) {
    this.lamps = lamps;
    this.size = size;
    this.maps = lamps.map((lamp) => {
      const target = new THREE.WebGLCubeRenderTarget(size, { type: THREE.FloatType, format: THREE.RGBAFormat });
      target.texture.minFilter = target.texture.magFilter = THREE.NearestFilter;
      target.texture.generateMipmaps = false;
      const camera = new THREE.CubeCamera(1e-3, 1e6, target);
      camera.position.copy(lamp.position);
      camera.updateMatrixWorld(true);
      return { target, camera };
    });
    const packed = packLights(lamps, MAX_DRAWN_LAMPS);
    this.uniforms = {
      drawnLampCount: { value: lamps.length },
      drawnLampColor: { value: packed.color },
      drawnLampPosition: { value: packed.position },
      drawnLampDirection: { value: packed.direction },
      drawnLampShape: { value: packed.shape },
      drawnLampMap0: { value: this.maps[0]?.target.texture ?? null },
      drawnLampMap1: { value: this.maps[1]?.target.texture ?? null },
      drawnLampTexelAngle: { value: (Math.PI / 2) / size },
    };
  }

  // Draws the distance maps. Each mesh draws with the distance material meanwhile: its own
  // may read these maps. (`world` may be a Group, which has no overrideMaterial.)
  render(renderer, world) {
    if (this.maps.length === 0) return;
    const own = new Map();
    world.traverse((object) => { if (object.isMesh) own.set(object, object.material); });
    const previous = { xr: renderer.xr.enabled, clear: renderer.getClearColor(new THREE.Color()), alpha: renderer.getClearAlpha() };
    renderer.xr.enabled = false;
    renderer.setClearColor(0x000000, 0);
    this.maps.forEach((map, k) => {
      const material = distanceMaterial(this.lamps[k].position);
      for (const object of own.keys()) object.material = material;
      map.camera.update(renderer, world);
      material.dispose();
    });
    for (const [object, mine] of own) object.material = mine;
    renderer.setClearColor(previous.clear, previous.alpha);
    renderer.xr.enabled = previous.xr;
  }
}

// Needs punctual.js PUNCTUAL_GLSL before it.
export const LAMP_SHADOW_GLSL = /* glsl */ `
uniform int drawnLampCount;
uniform vec4 drawnLampColor[${MAX_DRAWN_LAMPS}];
uniform vec4 drawnLampPosition[${MAX_DRAWN_LAMPS}];
uniform vec4 drawnLampDirection[${MAX_DRAWN_LAMPS}];
uniform vec4 drawnLampShape[${MAX_DRAWN_LAMPS}];
uniform highp samplerCube drawnLampMap0;
uniform highp samplerCube drawnLampMap1;
uniform float drawnLampTexelAngle;

// Whether lamp k sees p: the nearest surface along the way from the light, against p's own
// distance less a bias of two texels' width there (p pushed off its surface by as much).
float drawnLampVisibility(int k, vec3 p, vec3 ng) {
  vec3 d = p - drawnLampPosition[k].xyz;
  float distance0 = length(d);
  float slack = 2.0 * drawnLampTexelAngle * distance0;
  vec3 q = p + ng * slack - drawnLampPosition[k].xyz;
  float inverse = k == 0 ? textureLod(drawnLampMap0, q, 0.0).r : textureLod(drawnLampMap1, q, 0.0).r;
  if (!(inverse > 0.0)) return 1.0;
  return 1.0 / inverse < length(q) - slack ? 0.0 : 1.0;
}

// Σ over the drawn lamps of E·cos θ / π × visibility: what to add to the lightmap's E/π.
vec3 drawnLampLight(vec3 p, vec3 ng, vec3 ns) {
  vec3 sum = vec3(0.0);
  for (int k = 0; k < ${MAX_DRAWN_LAMPS}; ++k) {
    if (k >= drawnLampCount) break;
    vec3 e = punctualIrradiance(drawnLampColor[k], drawnLampPosition[k], drawnLampDirection[k], drawnLampShape[k], p, ng, ns);
    if (e == vec3(0.0)) continue;
    sum += e * (drawnLampVisibility(k, p, ng) / 3.14159265358979);
  }
  return sum;
}
`;
