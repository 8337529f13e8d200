// The punctual lights of a baked scene.glb that an engine draws itself (VOXLIGHT_light_bake,
// docs/light-bake-modes.md), and their unshadowed light in GLSL: what shadowmask.js,
// sun_shadows.js and lamp_shadows.js share.
import * as THREE from 'three';

const LUMENS_PER_WATT = 683;  // glTF's lux and candela to the bake's W/m² and W/sr (scene.h)
export const LIGHT_TYPE = { directional: 0, point: 1, spot: 2 };

// The lights of a GLTFLoader result whose VOXLIGHT_light_bake passes `wanted(definition, bake)`,
// placed where its scene puts them now, in the scene's order: each { type, definition, bake,
// color (radiometric intensity × colour), position, direction (the way its light travels),
// range, spotScale, spotOffset }.
export function bakedLights(gltf, wanted) {
  const json = gltf.parser.json;
  const definitions = json.extensions?.KHR_lights_punctual?.lights ?? [];
  const lights = [];
  gltf.scene.updateMatrixWorld(true);
  gltf.scene.traverse((object) => {
    const node = gltf.parser.associations.get(object)?.nodes;
    if (node === undefined) return;
    const definition = definitions[json.nodes[node]?.extensions?.KHR_lights_punctual?.light];
    const bake = definition?.extensions?.VOXLIGHT_light_bake;
    if (!definition || !bake || !wanted(definition, bake)) return;
    const colour = definition.color ?? [1, 1, 1];
    const watts = (definition.intensity ?? 1) / LUMENS_PER_WATT;
    const light = {
      type: LIGHT_TYPE[definition.type] ?? LIGHT_TYPE.point,
      definition,
      bake,
      color: new THREE.Vector3(colour[0] * watts, colour[1] * watts, colour[2] * watts),
      position: new THREE.Vector3().setFromMatrixPosition(object.matrixWorld),
      direction: new THREE.Vector3(0, 0, -1).transformDirection(object.matrixWorld),
      range: definition.range ?? 0,
      spotScale: 0,
      spotOffset: 1,
    };
    if (definition.type === 'spot') {
      // KHR_lights_punctual's smooth falloff between the cones (as the bake's TraceLight).
      const cosOuter = Math.cos(definition.spot?.outerConeAngle ?? Math.PI / 4);
      const cosInner = Math.cos(definition.spot?.innerConeAngle ?? 0);
      light.spotScale = 1 / Math.max(0.001, cosInner - cosOuter);
      light.spotOffset = -cosOuter * light.spotScale;
    }
    lights.push(light);
  });
  return lights;
}

// `lights` packed for PUNCTUAL_GLSL as uniform arrays of `length` vec4s each (see there), the
// rest zero; `extra(light)` goes into shape.z.
export function packLights(lights, length, extra = () => 0) {
  const vectors = () => Array.from({ length }, () => new THREE.Vector4());
  const packed = { color: vectors(), position: vectors(), direction: vectors(), shape: vectors() };
  lights.slice(0, length).forEach((light, k) => {
    packed.color[k].set(light.color.x, light.color.y, light.color.z, light.type);
    packed.position[k].set(light.position.x, light.position.y, light.position.z, light.range);
    packed.direction[k].set(light.direction.x, light.direction.y, light.direction.z, 0);
    packed.shape[k].set(light.spotScale, light.spotOffset, extra(light), 0);
  });
  return packed;
}

// E·cos θ of one light at p (normals unit, world space, on the side the camera sees), no
// shadow: glTF's inverse square falloff and range window, a spot's smooth cone, zero under
// either horizon. color: rgb W/m² or W/sr, w the type (0 directional, 1 point, 2 spot);
// position: xyz, w the range (0: none); direction: the way the light travels; shape: the
// spot's scale and offset.
export const PUNCTUAL_GLSL = /* glsl */ `
vec3 punctualIrradiance(vec4 color, vec4 position, vec4 direction, vec4 shape, vec3 p, vec3 ng, vec3 ns) {
  vec3 wi;
  float falloff = 1.0;
  if (color.w < 0.5) {
    wi = -direction.xyz;
  } else {
    vec3 d = position.xyz - p;
    float r2 = dot(d, d);
    if (!(r2 > 0.0)) return vec3(0.0);
    wi = d * inversesqrt(r2);
    float window = 1.0;
    if (position.w > 0.0) { float q = r2 / (position.w * position.w); window = clamp(1.0 - q * q, 0.0, 1.0); }
    falloff = window / r2;
    if (color.w > 1.5) {
      float t = clamp(dot(direction.xyz, -wi) * shape.x + shape.y, 0.0, 1.0);
      falloff *= t * t;
    }
  }
  float cosS = dot(ns, wi);
  if (cosS <= 0.0 || dot(ng, wi) <= 0.0) return vec3(0.0);
  return color.rgb * (falloff * cosS);
}
`;
