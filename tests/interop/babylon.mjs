// Babylon.js loads our .gltf with its own glTF loader into a NullEngine scene; prints what a
// white Lambertian surface shows at each glTF normal, and what its specular cube holds.
// Usage: node babylon.mjs JOB.json  with {"file", "normals": [[x, y, z], ...] (glTF axes),
// "rightHanded": bool, "turnLeftHanded": bool (the README's fix for left-handed scenes)}
import { readFileSync, writeFileSync } from "node:fs";
import { createRequire } from "node:module";
import { resolveObjectURL } from "node:buffer";
import { NullEngine } from "@babylonjs/core/Engines/nullEngine.js";
import { Scene } from "@babylonjs/core/scene.js";
import { InternalTexture } from "@babylonjs/core/Materials/Textures/internalTexture.js";
import { Matrix, Vector3 } from "@babylonjs/core/Maths/math.vector.js";
import { AppendSceneAsync } from "@babylonjs/core/Loading/sceneLoader.js";
import { PrepareDefinesForIBL } from "@babylonjs/core/Materials/materialHelper.functions.js";
import { ShaderStore } from "@babylonjs/core/Engines/shaderStore.js";
import { CubeMapToSphericalPolynomialTools } from "@babylonjs/core/Misc/HighDynamicRange/cubemapToSphericalPolynomial.js";
import "@babylonjs/core/Materials/Textures/baseTexture.polynomial.js";
import "@babylonjs/core/Shaders/ShadersInclude/harmonicsFunctions.js";
import "@babylonjs/core/Shaders/ShadersInclude/pbrBlockReflection.js";
import "@babylonjs/core/Shaders/ShadersInclude/reflectionFunction.js";
import "@babylonjs/loaders/glTF/2.0/index.js";
import { channelFunction, preprocess } from "./glsl.mjs";
import { decodePng } from "./png.mjs";

// The browser's Image, as Babylon's RGBD upload uses it: decode the blob URL's PNG.
globalThis.Image = class {
  set src(url) {
    resolveObjectURL(url).arrayBuffer().then((buffer) => {
      Object.assign(this, decodePng(new Uint8Array(buffer)));
      this.onload();
    }, (error) => this.onerror(error));
  }
};

const job = JSON.parse(readFileSync(process.argv[2], "utf8"));
const engine = new NullEngine();
// NullEngine has no createRawCubeTexture (the WebGL one calls gl): the same texture state,
// without a GPU. Everything else (loader, upload order and flags, decoding) is Babylon's own.
engine.createRawCubeTexture = function (data, size, format, type, generateMipMaps, invertY, samplingMode) {
  const texture = new InternalTexture(this, 8 /* InternalTextureSource.CubeRaw */);
  Object.assign(texture, { isCube: true, format, type, width: size, height: size, baseWidth: size,
    baseHeight: size, invertY, generateMipMaps, samplingMode, isReady: true });
  this._internalTexturesCache.push(texture);
  return texture;
};
const uploads = [];
engine._uploadImageToTexture = (texture, image, face, lod) => {
  uploads.push({ texture, face, lod, invertY: texture.invertY, size: image.width, data: image.data });
};
const scene = new Scene(engine);
scene.useRightHandedSystem = job.rightHanded;
// A glTF node, loaded by the same loader: the world matrix its normals get in this scene
// (in a left-handed scene the loader parents glTF content to a mirroring "__root__").
const node = { asset: { version: "2.0" }, scene: 0, scenes: [{ nodes: [0] }], nodes: [{ name: "probe" }] };
const text = readFileSync(job.file, "utf8");
try {
  await AppendSceneAsync("data:" + JSON.stringify(node), scene, { pluginExtension: ".gltf" });
  await AppendSceneAsync("data:" + text, scene, { pluginExtension: ".gltf" });
} catch (error) {
  process.stderr.write(`Babylon's loader failed: ${error.innerError?.message ?? ""} ${error.message.slice(0, 300)}\n`);
  process.exit(3);
}
const env = scene.environmentTexture;
if (!env) throw new Error("the loader set no environment texture");
if (job.turnLeftHanded) Matrix.RotationYToRef(Math.PI, env.getReflectionTextureMatrix());

// The defines Babylon's PBR material derives from this texture (its own function).
const defines = {};
PrepareDefinesForIBL(scene, env, defines);
defines.SPHERICAL_HARMONICS = true; // PBRBRDFConfiguration.DEFAULT_USE_SPHERICAL_HARMONICS
const on = new Set(Object.keys(defines).filter((k) => defines[k] === true));

// The fragment shader's lookup vector: reflectionMatrix * normalW, then the define flips.
const block = ShaderStore.IncludesShadersStore.pbrBlockReflection;
for (const line of [
  "vec3 irradianceVector=vec3(reflectionMatrix*vec4(normalW,0)).xyz;",
  "#ifdef REFLECTIONMAP_OPPOSITEZ\nirradianceVector.z*=-1.0;",
  "#ifdef INVERTCUBICMAP\nirradianceVector.y*=-1.0;",
  "environmentIrradiance=computeEnvironmentIrradiance(irradianceVector);",
]) if (!block.includes(line)) throw new Error(`pbrBlockReflection changed: ${line}`);
const cubic = ShaderStore.IncludesShadersStore.reflectionFunction;
if (!cubic.includes("vec3 coords=reflect(viewDir,worldNormal);coords=vec3(reflectionMatrix*vec4(coords,0));"))
  throw new Error("computeCubicCoords changed");
if (!block.includes("#ifdef REFLECTIONMAP_OPPOSITEZ\nreflectionVector.z*=-1.0;"))
  throw new Error("createReflectionCoords changed");
const harmonics = preprocess(ShaderStore.IncludesShadersStore.harmonicsFunctions, on);
const names = ["vSphericalL00", "vSphericalL1_1", "vSphericalL10", "vSphericalL11", "vSphericalL2_2",
  "vSphericalL2_1", "vSphericalL20", "vSphericalL21", "vSphericalL22"];
const irradianceAt = channelFunction(harmonics, "computeEnvironmentIrradiance", names);
const keys = ["l00", "l1_1", "l10", "l11", "l2_2", "l2_1", "l20", "l21", "l22"];

const world = scene.getNodeByName("probe").computeWorldMatrix(true);
const reflection = env.getReflectionTextureMatrix();
const level = env.level * scene.iblIntensity; // vReflectionInfos.x

function lookup(v) { // world vector -> cube lookup vector (fragment shader)
  const r = Vector3.TransformNormal(v, reflection);
  if (on.has("REFLECTIONMAP_OPPOSITEZ")) r.z *= -1;
  if (on.has("INVERTCUBICMAP")) r.y *= -1;
  return r;
}
function diffuse(harm) {
  return job.normals.map(([x, y, z]) => {
    const normalW = Vector3.TransformNormal(new Vector3(x, y, z), world).normalize();
    const n = lookup(normalW);
    return ["x", "y", "z"].map((c) => level * irradianceAt(n, ...keys.map((k) => harm[k][c])));
  });
}

// The specular cube as uploaded (face, level, row order) and Babylon's own CPU reading of
// its level 0 into spherical harmonics (the faces' orientation as Babylon defines it).
const mine = uploads.filter((u) => u.texture === env.getInternalTexture());
const level0 = mine.filter((u) => u.lod === 0).sort((a, b) => a.face - b.face);
if (level0.length !== 6) throw new Error(`level 0 has ${level0.length} faces uploaded`);
const size = level0[0].size;
const faceData = level0.map((u) => {
  const f = new Float32Array(size * size * 4);
  for (let y = 0; y < size; y++) {
    const src = u.invertY ? size - 1 - y : y; // UNPACK_FLIP_Y: the image's last row is t = 0
    for (let x = 0; x < size; x++) for (let k = 0; k < 4; k++) {
      const rgbd = u.data.subarray((src * size + x) * 4, (src * size + x) * 4 + 4);
      f[(y * size + x) * 4 + k] = k < 3 ? Math.pow(rgbd[k] / 255, 2.2) / (rgbd[3] / 255) : 1; // fromRGBD
    }
  }
  return f;
});
const cubeInfo = { size, right: faceData[0], left: faceData[1], up: faceData[2], down: faceData[3],
  front: faceData[4], back: faceData[5], format: 5, type: 1, gammaSpace: false };
const fromCube = CubeMapToSphericalPolynomialTools.ConvertCubeMapToSphericalPolynomial(cubeInfo);

// Where the brightest texel of level 0 is seen: its lookup direction (WebGL cube-map
// selection, t = 0 at the first row as uploaded) back through the shader to a world
// direction and through the loader's root node to glTF axes.
let best = { v: -1 };
faceData.forEach((f, face) => {
  for (let i = 0; i < size * size; i++) {
    const v = f[i * 4] + f[i * 4 + 1] + f[i * 4 + 2];
    if (v > best.v) best = { v, face, x: i % size, y: Math.floor(i / size) };
  }
});
const sc = (2 * (best.x + 0.5)) / size - 1, tc = (2 * (best.y + 0.5)) / size - 1;
const faceDir = [[1, -tc, -sc], [-1, -tc, sc], [sc, 1, tc], [sc, -1, -tc], [sc, -tc, 1], [-sc, -tc, -1]][best.face];
const l = new Vector3(...faceDir).normalize();
if (on.has("INVERTCUBICMAP")) l.y *= -1;
if (on.has("REFLECTIONMAP_OPPOSITEZ")) l.z *= -1;
const inverseReflection = reflection.clone().invert();
const inverseWorld = world.clone().invert();
const brightGltf = Vector3.TransformNormal(Vector3.TransformNormal(l, inverseReflection), inverseWorld).normalize();

writeFileSync(job.output, JSON.stringify({
  version: createRequire(import.meta.url)("@babylonjs/core/package.json").version,
  loaders: createRequire(import.meta.url)("@babylonjs/loaders/package.json").version,
  defines: [...on].filter((k) => /OPPOSITEZ|INVERTCUBIC|SPHERICAL|RGBD|LODBASED/.test(k)),
  lodGenerationScale: env.lodGenerationScale,
  levels: [...new Set(mine.map((u) => u.lod))].length,
  sizes: [...new Set(mine.map((u) => u.size))],
  diffuse: diffuse(env.sphericalPolynomial.preScaledHarmonics),
  diffuseFromCube: diffuse(fromCube.preScaledHarmonics),
  brightest: [brightGltf.x, brightGltf.y, brightGltf.z],
}));
