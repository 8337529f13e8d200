// voxlight's lightmaps in your own three.js scene: copy this file beside your code.
//
//   import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
//   import { applyMozLightmaps } from './moz_lightmap.js';
//   const gltf = await new GLTFLoader().loadAsync('scene.glb');
//   await applyMozLightmaps(gltf);
//   scene.add(gltf.scene);  // no lights needed: the lighting is baked
//
// Each material carrying MOZ_lightmap ({index, texCoord, intensity}) becomes a
// MeshBasicMaterial with the same colour, texture, vertex colours, sides and alpha, its
// lightMap on the UV set texCoord names (TEXCOORD_1) and lightMapIntensity π: three.js'
// basic material reflects albedo × lightmap × intensity / π, and voxlight's lightmap holds
// E/π, so a surface shows albedo × lightmap, the bake's outgoing radiance. The lightmap is
// RGBM (lightmap = rgb · a · intensity, linear, no sRGB curve): the decode is spliced into
// three.js' shader where it reads the lightmap. (MeshStandardMaterial would take the same
// lightMap but darkens its diffuse by its own specular term, a few percent.) The page of
// `voxlight view` draws with a shader of its own that filters decoded texels; this file is
// the shorter way, and the browser test holds both to the bake's image.
import * as THREE from 'three';

async function lightmapTexture(parser, index, cache) {
  if (!cache.has(index)) {
    cache.set(index, parser.getDependency('texture', index).then((shared) => {
      const texture = shared.clone();  // the image may serve as a colour map elsewhere
      texture.colorSpace = THREE.NoColorSpace;
      texture.flipY = false;
      texture.generateMipmaps = false;  // mips of RGBM texels would average encodings, not light
      texture.minFilter = THREE.LinearFilter;
      texture.needsUpdate = true;
      return texture;
    }));
  }
  return cache.get(index);
}

function basicWithLightmap(source, texture, extension) {
  texture = texture.clone();
  texture.channel = extension.texCoord ?? 0;
  const material = new THREE.MeshBasicMaterial({
    name: source.name,
    color: source.color,
    map: source.map,
    vertexColors: source.vertexColors,
    side: source.side,
    transparent: source.transparent,
    opacity: source.opacity,
    alphaTest: source.alphaTest,
    depthWrite: source.depthWrite,
    lightMap: texture,
    lightMapIntensity: Math.PI,
  });
  const range = extension.intensity ?? 1;
  material.onBeforeCompile = (shader) => {
    shader.uniforms.lightMapRange = { value: range };
    shader.fragmentShader = 'uniform float lightMapRange;\n' + shader.fragmentShader.replace(
      'vec4 lightMapTexel = texture2D( lightMap, vLightMapUv );',
      'vec4 lightMapTexel = texture2D( lightMap, vLightMapUv );\n' +
      'lightMapTexel = vec4( lightMapTexel.rgb * lightMapTexel.a * lightMapRange, 1.0 );');
  };
  material.customProgramCacheKey = () => 'voxlight-rgbm';
  return material;
}

// Replaces the materials of gltf.scene (from GLTFLoader) that carry MOZ_lightmap; returns how
// many meshes it changed.
export async function applyMozLightmaps(gltf) {
  const parser = gltf.parser;
  const textures = new Map();
  const made = new Map();
  const meshes = [];
  gltf.scene.traverse((object) => { if (object.isMesh) meshes.push(object); });
  let changed = 0;
  for (const mesh of meshes) {
    const sources = Array.isArray(mesh.material) ? mesh.material : [mesh.material];
    const replaced = [];
    for (const source of sources) {
      const association = parser.associations.get(source);
      const definition = association && association.materials !== undefined ? parser.json.materials[association.materials] : null;
      const extension = definition && definition.extensions && definition.extensions.MOZ_lightmap;
      if (!extension) { replaced.push(source); continue; }
      if (!made.has(source)) made.set(source, basicWithLightmap(source, await lightmapTexture(parser, extension.index, textures), extension));
      replaced.push(made.get(source));
    }
    if (replaced.some((m, i) => m !== sources[i])) ++changed;
    mesh.material = Array.isArray(mesh.material) ? replaced : replaced[0];
  }
  return changed;
}
