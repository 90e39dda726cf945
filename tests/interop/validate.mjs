// The Khronos glTF validator and the extension's JSON schema (ext_lights_image_based.schema.json)
// on one .gltf file. Usage: node validate.mjs JOB.json, JOB = {"file", "output"}
import { readFileSync, writeFileSync } from "node:fs";
import { createRequire } from "node:module";
import Ajv from "ajv";

const require = createRequire(import.meta.url);
const validator = require("gltf-validator");
const { file, output } = JSON.parse(readFileSync(process.argv[2], "utf8"));
const text = readFileSync(file, "utf8");
const report = await validator.validateString(text, { uri: file, maxIssues: 100 });
const schema = JSON.parse(readFileSync(new URL("./ext_lights_image_based.schema.json", import.meta.url), "utf8"));
const ajv = new Ajv({ allErrors: true, strict: false });
const check = ajv.compile(schema);
const valid = check(JSON.parse(text));
writeFileSync(output, JSON.stringify({
  validatorVersion: validator.version(),
  ajvVersion: require("ajv/package.json").version,
  issues: report.issues,
  resources: report.info?.resources ?? [],
  schemaValid: valid,
  schemaErrors: check.errors ?? [],
}));
