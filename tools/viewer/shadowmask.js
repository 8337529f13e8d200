// Shadowmask lights in three.js: the direct light an engine draws for a light whose bake mode
// is "shadowmask" (VOXLIGHT_light_bake, docs/light-bake-modes.md). The lightmap holds its
// indirect light; the engine adds its unshadowed direct light E·cos θ / π (glTF's falloff,
// range window and spot cone, radiometric: the file's lux and candela ÷ 683) times the light's
// channel of the material's shadowmask (VOXLIGHT_shadowmask: 8-bit linear RGBA on TEXCOORD_1),
// read bilinearly between texel centres as the lightmap is. `voxlight view` draws its surfaces
// with this chunk; for one's own shader:
//
//   import { shadowmaskLights, shadowmaskUniforms, SHADOWMASK_GLSL } from './shadowmask.js';
//   const lights = shadowmaskLights(gltf);             // after GLTFLoader, scene placed
//   material.uniforms = { ...material.uniforms, ...shadowmaskUniforms(lights, maskTexture) };
//   // fragment shader: SHADOWMASK_GLSL, then
//   //   light += shadowmaskLight(worldPosition, geometricNormal, shadingNormal, lightmapUv);
//   // the normals unit, world space, on the side the camera sees.
//
// maskTexture: the VOXLIGHT_shadowmask texture with colorSpace NoColorSpace, flipY false,
// NearestFilter and no mipmaps (the chunk filters it itself).
import * as THREE from 'three';

export const MAX_SHADOWMASK_LIGHTS = 4;
const LUMENS_PER_WATT = 683;  // glTF's photometric units to the bake's radiometric ones (scene.h)
const TYPE = { directional: 0, point: 1, spot: 2 };

// The shadowmask lights of a GLTFLoader result, placed where its scene puts them now: each
// { type, channel, color (radiometric intensity × colour), position, direction (travelled),
// range, spotScale, spotOffset }.
export function shadowmaskLights(gltf) {
  const json = gltf.parser.json;
  const definitions = json.extensions?.KHR_lights_punctual?.lights ?? [];
  const lights = [];
  gltf.scene.updateMatrixWorld(true);
  gltf.scene.traverse((object) => {
    const node = gltf.parser.associations.get(object)?.nodes;
    if (node === undefined) return;
    const index = json.nodes[node]?.extensions?.KHR_lights_punctual?.light;
    const definition = definitions[index];
    const bake = definition?.extensions?.VOXLIGHT_light_bake;
    if (!bake || bake.mode !== 'shadowmask' || !(bake.channel >= 0 && bake.channel < MAX_SHADOWMASK_LIGHTS)) return;
    const colour = definition.color ?? [1, 1, 1];
    const watts = (definition.intensity ?? 1) / LUMENS_PER_WATT;
    const light = {
      type: TYPE[definition.type] ?? 1,
      channel: bake.channel,
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
  return lights.slice(0, MAX_SHADOWMASK_LIGHTS);
}

// The chunk's uniforms for `lights` (shadowmaskLights) and a material's shadowmask texture.
export function shadowmaskUniforms(lights, texture) {
  const vectors = () => Array.from({ length: MAX_SHADOWMASK_LIGHTS }, () => new THREE.Vector4());
  const color = vectors(), position = vectors(), direction = vectors(), shape = vectors();
  lights.forEach((light, k) => {
    color[k].set(light.color.x, light.color.y, light.color.z, light.type);
    position[k].set(light.position.x, light.position.y, light.position.z, light.range);
    direction[k].set(light.direction.x, light.direction.y, light.direction.z, 0);
    shape[k].set(light.spotScale, light.spotOffset, light.channel, 0);
  });
  return {
    shadowMask: { value: texture },
    maskLightCount: { value: texture ? lights.length : 0 },
    maskLightColor: { value: color },
    maskLightPosition: { value: position },
    maskLightDirection: { value: direction },
    maskLightShape: { value: shape },
  };
}

export const SHADOWMASK_GLSL = /* glsl */ `
uniform sampler2D shadowMask;
uniform int maskLightCount;
uniform vec4 maskLightColor[${MAX_SHADOWMASK_LIGHTS}];      // rgb: W/m² or W/sr; w: 0 directional, 1 point, 2 spot
uniform vec4 maskLightPosition[${MAX_SHADOWMASK_LIGHTS}];   // xyz; w: range (0: none)
uniform vec4 maskLightDirection[${MAX_SHADOWMASK_LIGHTS}];  // the way its light travels
uniform vec4 maskLightShape[${MAX_SHADOWMASK_LIGHTS}];      // spot scale, spot offset, mask channel

vec4 shadowMaskTexel(ivec2 p, ivec2 size) { return texelFetch(shadowMask, clamp(p, ivec2(0), size - 1), 0); }

// Bilinear between texel centres at (i + 0.5) / size, as the lightmap.
vec4 shadowMaskAt(vec2 uv) {
  ivec2 size = textureSize(shadowMask, 0);
  vec2 p = uv * vec2(size) - 0.5;
  vec2 cell = floor(p);
  vec2 f = p - cell;
  ivec2 i = ivec2(cell);
  vec4 bottom = mix(shadowMaskTexel(i, size), shadowMaskTexel(i + ivec2(1, 0), size), f.x);
  vec4 top = mix(shadowMaskTexel(i + ivec2(0, 1), size), shadowMaskTexel(i + ivec2(1, 1), size), f.x);
  return mix(bottom, top, f.y);
}

// Σ over the shadowmask lights of E·cos θ / π × mask: what to add to the lightmap's E/π.
vec3 shadowmaskLight(vec3 p, vec3 ng, vec3 ns, vec2 uv) {
  if (maskLightCount == 0) return vec3(0.0);
  vec4 mask = shadowMaskAt(uv);
  vec3 sum = vec3(0.0);
  for (int k = 0; k < ${MAX_SHADOWMASK_LIGHTS}; ++k) {
    if (k >= maskLightCount) break;
    vec3 wi;
    float falloff = 1.0;
    if (maskLightColor[k].w < 0.5) {
      wi = -maskLightDirection[k].xyz;
    } else {
      vec3 d = maskLightPosition[k].xyz - p;
      float r2 = dot(d, d);
      if (!(r2 > 0.0)) continue;
      wi = d * inversesqrt(r2);
      float range = maskLightPosition[k].w;
      float window = 1.0;
      if (range > 0.0) { float q = r2 / (range * range); window = clamp(1.0 - q * q, 0.0, 1.0); }
      falloff = window / r2;
      if (maskLightColor[k].w > 1.5) {
        float t = clamp(dot(maskLightDirection[k].xyz, -wi) * maskLightShape[k].x + maskLightShape[k].y, 0.0, 1.0);
        falloff *= t * t;
      }
    }
    float cosS = dot(ns, wi);
    if (cosS <= 0.0 || dot(ng, wi) <= 0.0) continue;
    sum += maskLightColor[k].rgb * (falloff * cosS / 3.14159265358979) * mask[int(maskLightShape[k].z)];
  }
  return sum;
}
`;
