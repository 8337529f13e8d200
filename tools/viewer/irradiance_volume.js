// voxlight's irradiance volume in three.js: light for what the bake did not see (a dynamic
// object, a model dropped in), from the probes of VOXLIGHT_irradiance_volume in scene.glb.
//
//   import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
//   import { loadIrradianceVolume } from './irradiance_volume.js';
//   const gltf = await new GLTFLoader().loadAsync('scene.glb');
//   const volume = await loadIrradianceVolume(gltf);   // null: the bake has no volume
//   const ball = new THREE.Mesh(new THREE.SphereGeometry(0.1, 64, 32),
//                               volume.material({ color: new THREE.Color(0.8, 0.8, 0.8) }, { exposure: 1 }));
//   scene.add(ball);   // world metres: the volume is placed in the frame of the glTF's root
//   // a loaded model: mesh.material = volume.material(mesh.material) for each of its meshes
//
// Each probe holds per colour channel E(n)/π ≈ A + B·n over normals n (A in the lightmap's
// convention E/π, B in world axes), and how much it sees of each sun the file keeps apart
// (`suns`, up to four). A fragment interpolates these trilinearly over the 8 probes around it,
// weighing out the probes inside geometry, and turns A and B into E/π with the non-linear
// reconstruction (Hazel, Geomerics), which keeps the mean and is never negative; each
// sun adds its E·max(0, n·ω)/π times its visibility. The material draws albedo × E/π +
// emission, times the exposure, through the sRGB curve, clamped, exactly as `voxlight view`
// draws its baked surfaces: it writes display values itself, so draw it straight to the
// canvas. For a shader of one's own: IRRADIANCE_VOLUME_GLSL and `volume.uniforms`, then
// `vec3 volumeIrradiance(vec3 worldPosition, vec3 unitWorldNormal)`.
//
// The images (RGBM, gradients, validity) are decoded here from the PNG bytes, not through a
// canvas: a 2D canvas keeps premultiplied colour, which would lose the RGBM texels of small alpha.
import * as THREE from 'three';

const EXTENSION = 'VOXLIGHT_irradiance_volume';
export const MAX_VOLUME_SUNS = 4;

// ---- PNG bytes to 8-bit samples -----------------------------------------------------------

const PNG_CHANNELS = { 0: 1, 2: 3, 4: 2, 6: 4 };  // colour type: grey, RGB, grey+alpha, RGBA

function paeth(a, b, c) {
  const p = a + b - c;
  const pa = Math.abs(p - a), pb = Math.abs(p - b), pc = Math.abs(p - c);
  return pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
}

// An 8-bit, non-interlaced, non-palette PNG: { width, height, channels, data } with data row by
// row from the top, the samples as stored.
async function decodePng(bytes) {
  const signature = [137, 80, 78, 71, 13, 10, 26, 10];
  if (!signature.every((b, i) => bytes[i] === b)) throw new Error(`${EXTENSION}: an image is not a PNG`);
  const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  const compressed = [];
  let header = null;
  for (let at = 8; at + 8 <= bytes.length;) {
    const length = view.getUint32(at);
    const type = String.fromCharCode(...bytes.subarray(at + 4, at + 8));
    const body = bytes.subarray(at + 8, at + 8 + length);
    if (type === 'IHDR')
      header = { width: view.getUint32(at + 8), height: view.getUint32(at + 12), depth: body[8], type: body[9], interlace: body[12] };
    else if (type === 'IDAT') compressed.push(body);
    else if (type === 'IEND') break;
    at += 12 + length;
  }
  const channels = header && PNG_CHANNELS[header.type];
  if (!channels || header.depth !== 8 || header.interlace !== 0)
    throw new Error(`${EXTENSION}: the images must be 8-bit, non-interlaced grey, RGB or RGBA PNGs`);
  const inflated = new Uint8Array(await new Response(
    new Blob(compressed).stream().pipeThrough(new DecompressionStream('deflate'))).arrayBuffer());
  const { width, height } = header;
  const stride = width * channels;
  if (inflated.length < height * (stride + 1)) throw new Error(`${EXTENSION}: a PNG is truncated`);
  const data = new Uint8Array(height * stride);
  for (let y = 0; y < height; ++y) {
    const filter = inflated[y * (stride + 1)];
    const source = inflated.subarray(y * (stride + 1) + 1, (y + 1) * (stride + 1));
    const row = y * stride;
    for (let x = 0; x < stride; ++x) {
      const left = x >= channels ? data[row + x - channels] : 0;
      const up = y > 0 ? data[row - stride + x] : 0;
      const upLeft = y > 0 && x >= channels ? data[row - stride + x - channels] : 0;
      const predicted = filter === 0 ? 0 : filter === 1 ? left : filter === 2 ? up
                      : filter === 3 ? (left + up) >> 1 : paeth(left, up, upLeft);
      data[row + x] = (source[x] + predicted) & 255;
    }
  }
  return { width, height, channels, data };
}

// ---- the extension ------------------------------------------------------------------------

async function imageBytes(parser, index) {
  const image = parser.json.images?.[index];
  if (!image) throw new Error(`${EXTENSION}: no image ${index}`);
  if (image.bufferView !== undefined) return new Uint8Array(await parser.getDependency('bufferView', image.bufferView));
  const response = await fetch(THREE.LoaderUtils.resolveURL(image.uri, parser.options.path));
  if (!response.ok) throw new Error(`${EXTENSION}: ${image.uri}: ${response.status}`);
  return new Uint8Array(await response.arrayBuffer());
}

function probeTexture(data, counts) {
  const texture = new THREE.Data3DTexture(data, counts[0], counts[1], counts[2]);
  texture.format = THREE.RGBAFormat;
  texture.type = THREE.FloatType;
  texture.minFilter = texture.magFilter = THREE.NearestFilter;  // interpolated in the shader, by validity
  texture.unpackAlignment = 1;
  texture.needsUpdate = true;
  return texture;
}

// The volume of a GLTFLoader result, or null when its file has none.
export async function loadIrradianceVolume(gltf) {
  const definition = gltf.parser.json.extensions?.[EXTENSION];
  if (!definition) return null;
  const counts = definition.counts.map(Number);
  const [nx, ny, nz] = counts;
  if (!counts.every((n) => Number.isInteger(n) && n >= 1)) throw new Error(`${EXTENSION}: bad counts ${definition.counts}`);
  const suns = (definition.suns ?? []).slice(0, MAX_VOLUME_SUNS);
  const indices = [definition.irradiance, ...definition.gradient, definition.valid];
  if (suns.length > 0) indices.push(definition.sunVisibility);
  const images = await Promise.all(indices.map(async (index) => decodePng(await imageBytes(gltf.parser, index))));
  for (const image of images)
    if (image.width !== nx || image.height !== ny * nz)
      throw new Error(`${EXTENSION}: an image is ${image.width} × ${image.height}, not ${nx} × ${ny * nz} (counts ${counts})`);
  const [irradiance, gx, gy, gz, valid, sunImage] = images;
  if (sunImage && sunImage.channels !== 4) throw new Error(`${EXTENSION}: the sunVisibility image must be RGBA`);
  if (irradiance.channels !== 4) throw new Error(`${EXTENSION}: the irradiance image must be RGBA (RGBM)`);
  if ([gx, gy, gz].some((g) => g.channels < 3)) throw new Error(`${EXTENSION}: the gradient images must be RGB or RGBA`);

  // Texel (i, j, k) of the 3D textures is probe (i, j, k): pixel column i, row j·nz + k.
  const range = Number(definition.range ?? 1);
  const mean = new Float32Array(nx * ny * nz * 4);  // rgb: A; a: validity
  const gradients = [0, 1, 2].map(() => new Float32Array(nx * ny * nz * 4));  // per colour channel: B
  const seen = new Float32Array(nx * ny * nz * 4);  // channel s: sun s's visibility
  for (let k = 0; k < nz; ++k)
    for (let j = 0; j < ny; ++j)
      for (let i = 0; i < nx; ++i) {
        const pixel = (j * nz + k) * nx + i;
        const texel = ((k * ny + j) * nx + i) * 4;
        const p = pixel * 4;
        const scale = (irradiance.data[p + 3] / 255) * range;
        for (let c = 0; c < 3; ++c) {
          const a = (irradiance.data[p + c] / 255) * scale;
          mean[texel + c] = a;
          [gx, gy, gz].forEach((g, axis) => {
            gradients[c][texel + axis] = a * 2 * ((g.data[pixel * g.channels + c] - 127) / 127);
          });
        }
        mean[texel + 3] = valid.data[pixel * valid.channels] / 255;
        for (let c = 0; c < 4; ++c) seen[texel + c] = sunImage ? sunImage.data[p + c] / 255 : 0;
      }
  return new IrradianceVolume(definition, counts, mean, gradients, suns, seen);
}

export class IrradianceVolume {
  constructor(definition, counts, mean, gradients, suns, seen) {
    this.origin = new THREE.Vector3().fromArray(definition.origin.map(Number));
    this.spacing = new THREE.Vector3().fromArray(definition.spacing.map(Number));
    this.counts = counts;
    this.textures = [probeTexture(mean, counts), ...gradients.map((g) => probeTexture(g, counts)), probeTexture(seen, counts)];
    const direction = [], irradiance = [];
    for (let s = 0; s < MAX_VOLUME_SUNS; ++s) {
      const sun = suns[s];
      direction.push(new THREE.Vector3().fromArray(sun ? sun.direction.map(Number) : [0, -1, 0]).normalize());
      irradiance.push(new THREE.Vector3().fromArray(sun ? sun.irradiance.map(Number) : [0, 0, 0]));
    }
    this.suns = suns.length;
    this.uniforms = {
      volumeMean: { value: this.textures[0] },
      volumeGradientR: { value: this.textures[1] },
      volumeGradientG: { value: this.textures[2] },
      volumeGradientB: { value: this.textures[3] },
      volumeOrigin: { value: this.origin },
      volumeSpacing: { value: this.spacing },
      volumeCounts: { value: new THREE.Vector3(...counts) },
      volumeSunVisibility: { value: this.textures[4] },
      volumeSunDirection: { value: direction },
      volumeSunIrradiance: { value: irradiance },
    };
  }

  // A diffuse material lit by the volume. `source`: a three.js material as GLTFLoader makes them
  // (color, opacity, map, emissive, emissiveIntensity, emissiveMap, vertexColors, alphaTest,
  // transparent, side), or an object with some of those. Options: exposure (a factor, 2^stops,
  // or a { value } uniform to share), mode (0 lit, 1 the light E/π alone, 2 albedo; a number or
  // a uniform), linear (the plain max(0, A + B·n) instead of the non-linear reconstruction).
  material(source = {}, { exposure = 1, mode = 0, linear = false } = {}) {
    const uniform = (v) => (typeof v === 'object' ? v : { value: v });
    const color = source.color ?? new THREE.Color(1, 1, 1);
    const emissive = source.emissive ? source.emissive.clone().multiplyScalar(source.emissiveIntensity ?? 1) : new THREE.Color(0, 0, 0);
    const defines = {};
    if (source.map) defines.HAS_BASE_MAP = '';
    if (source.emissiveMap) defines.HAS_EMISSIVE_MAP = '';
    if (source.map?.channel === 1 || source.emissiveMap?.channel === 1) defines.READS_UV1 = '';
    defines.BASE_UV = source.map?.channel === 1 ? 'uv1' : 'uv';
    defines.EMISSIVE_UV = source.emissiveMap?.channel === 1 ? 'uv1' : 'uv';
    if (source.alphaTest > 0) defines.ALPHA_MASK = '';
    if (source.transparent) defines.ALPHA_BLEND = '';
    if (linear) defines.IRRADIANCE_VOLUME_LINEAR = '';
    return new THREE.ShaderMaterial({
      name: source.name ?? 'irradiance volume',
      vertexShader: VERTEX_SHADER,
      fragmentShader: FRAGMENT_SHADER,
      defines,
      vertexColors: !!source.vertexColors,
      side: source.side ?? THREE.FrontSide,
      transparent: !!source.transparent,
      depthWrite: source.depthWrite ?? true,
      uniforms: {
        ...this.uniforms,
        baseColorFactor: { value: new THREE.Vector4(color.r, color.g, color.b, source.opacity ?? 1) },
        baseColorMap: { value: source.map ?? null },
        baseMapTransform: { value: textureMatrix(source.map) },
        emissiveFactor: { value: emissive },
        emissiveMap: { value: source.emissiveMap ?? null },
        emissiveMapTransform: { value: textureMatrix(source.emissiveMap) },
        alphaCutoff: { value: source.alphaTest ?? 0 },
        exposure: uniform(exposure),
        mode: uniform(mode),
      },
    });
  }

  dispose() {
    for (const texture of this.textures) texture.dispose();
  }
}

function textureMatrix(texture) {
  if (!texture) return new THREE.Matrix3();
  texture.updateMatrix();
  return texture.matrix;
}

// ---- GLSL ---------------------------------------------------------------------------------

// `volumeIrradiance(worldPosition, unitWorldNormal)`: E/π at a point, RGB, from the uniforms of
// `volume.uniforms`. WebGL2.
export const IRRADIANCE_VOLUME_GLSL = /* glsl */ `
uniform highp sampler3D volumeMean;       // rgb: A (E/π, the mean over normals); a: validity, 0..1
uniform highp sampler3D volumeGradientR;  // xyz: B of the red channel, world axes
uniform highp sampler3D volumeGradientG;
uniform highp sampler3D volumeGradientB;
uniform vec3 volumeOrigin;
uniform vec3 volumeSpacing;
uniform vec3 volumeCounts;
uniform highp sampler3D volumeSunVisibility;  // channel s: how much of sun s a probe sees
uniform vec3 volumeSunDirection[4];           // each sun's direction of travel, world, unit
uniform vec3 volumeSunIrradiance[4];          // and its E/π facing it (0: no sun)

// E/π toward n from one channel's A and B: Hazel's non-linear lobe, or the plain linear one.
float volumeLobe(float a0, vec3 b, vec3 n) {
#ifdef IRRADIANCE_VOLUME_LINEAR
  return max(a0 + dot(b, n), 0.0);
#else
  vec3 r1 = 0.5 * b;
  float length1 = length(r1);
  if (a0 <= 0.0 || length1 <= 1e-6 * a0) return max(a0, 0.0);
  float r = min(length1 / a0, 1.0);
  float q = clamp(0.5 * (1.0 + dot(r1 / length1, n)), 0.0, 1.0);
  float p = 1.0 + 2.0 * r;
  float a = (1.0 - r) / (1.0 + r);
  return a0 * (a + (1.0 - a) * (p + 1.0) * pow(q, p));
#endif
}

vec3 volumeIrradiance(vec3 worldPosition, vec3 worldNormal) {
  ivec3 last = ivec3(volumeCounts) - 1;
  vec3 g = clamp((worldPosition - volumeOrigin) / max(volumeSpacing, vec3(1e-20)), vec3(0.0), vec3(last));
  ivec3 cell = min(ivec3(floor(g)), max(last - 1, ivec3(0)));
  vec3 f = g - vec3(cell);
  // Two sums: weighed by validity, and plain for a cell whose 8 probes are all invalid. A valid
  // probe weighs at least 1e-6 of its trilinear share, so that a point on the face of invalid
  // probes (the grid's clamped edge) still takes the valid ones behind it.
  vec3 a = vec3(0.0), br = vec3(0.0), bg = vec3(0.0), bb = vec3(0.0);
  vec3 plainA = vec3(0.0), plainR = vec3(0.0), plainG = vec3(0.0), plainB = vec3(0.0);
  vec4 seen = vec4(0.0), plainSeen = vec4(0.0);
  float sum = 0.0;
  for (int corner = 0; corner < 8; ++corner) {
    ivec3 o = ivec3(corner & 1, (corner >> 1) & 1, corner >> 2);
    ivec3 probe = min(cell + o, last);
    vec3 w3 = mix(1.0 - f, f, vec3(o));
    float w = w3.x * w3.y * w3.z;
    vec4 m = texelFetch(volumeMean, probe, 0);
    vec3 r = texelFetch(volumeGradientR, probe, 0).xyz;
    vec3 gr = texelFetch(volumeGradientG, probe, 0).xyz;
    vec3 b = texelFetch(volumeGradientB, probe, 0).xyz;
    vec4 s = texelFetch(volumeSunVisibility, probe, 0);
    plainA += w * m.rgb; plainR += w * r; plainG += w * gr; plainB += w * b; plainSeen += w * s;
    float v = m.a * max(w, 1e-6);
    a += v * m.rgb; br += v * r; bg += v * gr; bb += v * b; seen += v * s;
    sum += v;
  }
  if (sum > 0.0) {
    a /= sum; br /= sum; bg /= sum; bb /= sum; seen /= sum;
  } else {
    a = plainA; br = plainR; bg = plainG; bb = plainB; seen = plainSeen;
  }
  vec3 e = vec3(volumeLobe(a.r, br, worldNormal), volumeLobe(a.g, bg, worldNormal), volumeLobe(a.b, bb, worldNormal));
  for (int s = 0; s < 4; ++s) e += seen[s] * max(0.0, -dot(worldNormal, volumeSunDirection[s])) * volumeSunIrradiance[s];
  return e;
}
`;

// three.js' chunks place the vertex (skinning, morph targets, instancing, batching) as its own
// materials do; the colour and light are the viewer's.
const VERTEX_SHADER = /* glsl */ `
#include <common>
#include <batching_pars_vertex>
#include <color_pars_vertex>
#include <morphtarget_pars_vertex>
#include <skinning_pars_vertex>
#ifdef READS_UV1
attribute vec2 uv1;
#endif
uniform mat3 baseMapTransform;
uniform mat3 emissiveMapTransform;
varying vec2 vBaseUv;
varying vec2 vEmissiveUv;
varying vec3 vWorldPosition;
varying vec3 vWorldNormal;

void main() {
  vBaseUv = (baseMapTransform * vec3(BASE_UV, 1.0)).xy;
  vEmissiveUv = (emissiveMapTransform * vec3(EMISSIVE_UV, 1.0)).xy;
  #include <color_vertex>
  #include <morphinstance_vertex>
  #include <morphcolor_vertex>
  #include <batching_vertex>
  #include <beginnormal_vertex>
  #include <morphnormal_vertex>
  #include <skinbase_vertex>
  #include <skinnormal_vertex>
  #include <defaultnormal_vertex>
  #include <begin_vertex>
  #include <morphtarget_vertex>
  #include <skinning_vertex>
  #include <project_vertex>
  vec4 world = vec4(transformed, 1.0);
#ifdef USE_BATCHING
  world = batchingMatrix * world;
#endif
#ifdef USE_INSTANCING
  world = instanceMatrix * world;
#endif
  vWorldPosition = (modelMatrix * world).xyz;
#ifdef HAS_NORMAL
  vWorldNormal = inverseTransformDirection(transformedNormal, viewMatrix);
#else
  vWorldNormal = vec3(0.0);  // flat: the fragment takes its geometric normal
#endif
}
`;

const FRAGMENT_SHADER = /* glsl */ `
#include <color_pars_fragment>
uniform vec4 baseColorFactor;
uniform sampler2D baseColorMap;
uniform vec3 emissiveFactor;
uniform sampler2D emissiveMap;
uniform float alphaCutoff;
uniform float exposure;
uniform int mode;
varying vec2 vBaseUv;
varying vec2 vEmissiveUv;
varying vec3 vWorldPosition;
varying vec3 vWorldNormal;
${IRRADIANCE_VOLUME_GLSL}

vec3 toSrgb(vec3 c) {
  c = clamp(c, 0.0, 1.0);
  return mix(c * 12.92, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, step(vec3(0.0031308), c));
}

void main() {
  vec4 albedo = baseColorFactor;
#ifdef HAS_BASE_MAP
  albedo *= texture2D(baseColorMap, vBaseUv);  // an sRGB texture: sampled in linear light
#endif
#if defined(USE_COLOR_ALPHA)
  albedo *= vColor;
#elif defined(USE_COLOR)
  albedo.rgb *= vColor.rgb;
#endif
#ifdef ALPHA_MASK
  if (albedo.a < alphaCutoff) discard;
#endif
  vec3 emission = emissiveFactor;
#ifdef HAS_EMISSIVE_MAP
  emission *= texture2D(emissiveMap, vEmissiveUv).rgb;
#endif
  // The side the camera sees.
  vec3 n;
  if (dot(vWorldNormal, vWorldNormal) > 0.0) {
    n = normalize(vWorldNormal) * (gl_FrontFacing ? 1.0 : -1.0);
  } else {
    n = normalize(cross(dFdx(vWorldPosition), dFdy(vWorldPosition)));
    if (dot(n, cameraPosition - vWorldPosition) < 0.0) n = -n;
  }
  vec3 light = volumeIrradiance(vWorldPosition, n);
  vec3 radiance = mode == 0 ? albedo.rgb * light + emission : mode == 1 ? light : albedo.rgb;
#ifdef ALPHA_BLEND
  float alpha = albedo.a;
#else
  float alpha = 1.0;
#endif
  gl_FragColor = vec4(toSrgb(radiance * exposure), alpha);
}
`;
