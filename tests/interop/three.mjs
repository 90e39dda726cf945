// three.js reads our LightProbe file; prints what a white Lambertian surface shows at each
// normal (glTF / three.js world axes), per three.js release installed (package aliases).
// Usage: node three.mjs JOB.json, JOB = {"file", "normals": [[x, y, z], ...], "modules": [...],
// "output": where the results are written as JSON}
import { readFileSync, writeFileSync } from "node:fs";
import { channelFunction } from "./glsl.mjs";

const job = JSON.parse(readFileSync(process.argv[2], "utf8"));
const text = readFileSync(job.file, "utf8");
const results = {};

for (const name of job.modules) {
  const THREE = await import(name);
  const json = JSON.parse(text);
  // 1. the documented usage: ObjectLoader, and the constructor from the `sh` array
  const probe = new THREE.ObjectLoader().parse(json);
  if (!probe.isLightProbe) throw new Error(`${name}: ObjectLoader gave ${probe.type}`);
  const built = new THREE.LightProbe(
    new THREE.SphericalHarmonics3().fromArray(json.object.sh), json.object.intensity);
  // 2. SphericalHarmonics3.getIrradianceAt (E), times intensity, times BRDF_Lambert (1/π)
  const target = new THREE.Vector3();
  const cpu = job.normals.map(([x, y, z]) => {
    probe.sh.getIrradianceAt(new THREE.Vector3(x, y, z), target);
    return [target.x, target.y, target.z].map((v) => (v * probe.intensity) / Math.PI);
  });
  // 3. the shader chunk's own function, with the uniform three.js fills (sh · intensity)
  const chunk = THREE.ShaderChunk.lights_pars_begin;
  const common = THREE.ShaderChunk.common;
  if (!/vec3 BRDF_Lambert\( const in vec3 diffuseColor \) {\s*return RECIPROCAL_PI \* diffuseColor;/.test(common)) throw new Error("BRDF_Lambert changed");
  if (!/vec3 irradiance = shGetIrradianceAt\( worldNormal, lightProbe \);/.test(chunk))
    throw new Error("getLightProbeIrradiance changed");
  const shGetIrradianceAt = channelFunction(chunk, "shGetIrradianceAt");
  const uniform = built.sh.coefficients.map((c) => c.clone().multiplyScalar(built.intensity));
  const shader = job.normals.map(([x, y, z]) =>
    ["x", "y", "z"].map((k) => shGetIrradianceAt({ x, y, z }, uniform.map((c) => c[k])) / Math.PI));
  results[name] = { revision: THREE.REVISION, cpu, shader };
}
writeFileSync(job.output, JSON.stringify(results));
