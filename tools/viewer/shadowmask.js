// Shadowmask lights in three.js: the direct light an engine draws for a light whose bake mode
// is "shadowmask" (VOXLIGHT_light_bake, docs/light-bake-modes.md). The lightmap holds its
// indirect light; the engine adds its unshadowed direct light E·cos θ / π (glTF's falloff,
// range window and spot cone, radiometric: the file's lux and candela ÷ 683) times the light's
// channel of the material's shadowmask (VOXLIGHT_shadowmask: 8-bit linear RGBA on TEXCOORD_1),
// read bilinearly between texel centres as the lightmap is. `voxlight view` draws its surfaces
// with this chunk; for one's own shader:
//
//   import { PUNCTUAL_GLSL } from './punctual.js';
//   import { shadowmaskLights, shadowmaskUniforms, SHADOWMASK_GLSL } from './shadowmask.js';
//   const lights = shadowmaskLights(gltf);             // after GLTFLoader, scene placed
//   material.uniforms = { ...material.uniforms, ...shadowmaskUniforms(lights, maskTexture) };
//   // fragment shader: PUNCTUAL_GLSL, SHADOWMASK_GLSL, then
//   //   light += shadowmaskLight(worldPosition, geometricNormal, shadingNormal, lightmapUv);
//   // the normals unit, world space, on the side the camera sees.
//
// maskTexture: the VOXLIGHT_shadowmask texture with colorSpace NoColorSpace, flipY false,
// NearestFilter and no mipmaps (the chunk filters it itself).
import { bakedLights, packLights } from './punctual.js';

export const MAX_SHADOWMASK_LIGHTS = 4;

// The shadowmask lights of a GLTFLoader result, placed where its scene puts them now
// (punctual.js bakedLights), each with its `channel`.
export function shadowmaskLights(gltf) {
  return bakedLights(gltf, (definition, bake) => bake.mode === 'shadowmask' && bake.channel >= 0 &&
                                                 bake.channel < MAX_SHADOWMASK_LIGHTS)
    .map((light) => ({ ...light, channel: light.bake.channel }))
    .slice(0, MAX_SHADOWMASK_LIGHTS);
}

// The chunk's uniforms for `lights` (shadowmaskLights) and a material's shadowmask texture.
export function shadowmaskUniforms(lights, texture) {
  const packed = packLights(lights, MAX_SHADOWMASK_LIGHTS, (light) => light.channel);
  return {
    shadowMask: { value: texture },
    maskLightCount: { value: texture ? lights.length : 0 },
    maskLightColor: { value: packed.color },
    maskLightPosition: { value: packed.position },
    maskLightDirection: { value: packed.direction },
    maskLightShape: { value: packed.shape },
  };
}

// Needs punctual.js PUNCTUAL_GLSL before it.
export const SHADOWMASK_GLSL = /* glsl */ `
uniform highp sampler2D shadowMask;
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
    sum += punctualIrradiance(maskLightColor[k], maskLightPosition[k], maskLightDirection[k], maskLightShape[k], p, ng, ns) *
           (mask[int(maskLightShape[k].z)] / 3.14159265358979);
  }
  return sum;
}
`;
