#!/usr/bin/env node
// Validates a .glb or .gltf with the Khronos glTF validator (npm package `gltf-validator`,
// pinned in package.json; install with `npm ci` in this folder).
// Usage: node validate_gltf.mjs FILE [--json] [--strict]
// Prints the number of errors, warnings, infos and hints and every message; exits 0 when the
// report has no errors, 1 when it has, 2 when the file cannot be read or validated.
//
// The validator predates KHR_gaussian_splatting (Release Candidate), whose attribute semantics
// take the form `KHR_gaussian_splatting:NAME`; base glTF 2.0 only knew `_NAME` for such
// semantics, so the validator reports each as MESH_PRIMITIVE_INVALID_ATTRIBUTE. Those errors are
// listed as "tolerated" and not counted, but only for exactly the semantics the extension defines,
// on a primitive that carries the extension. --strict counts them too.
import { readFile } from 'node:fs/promises';
import path from 'node:path';
import { createRequire } from 'node:module';

const require = createRequire(import.meta.url);
let validator;
try {
  validator = require('gltf-validator');
} catch (e) {
  console.error(`validate_gltf: cannot load gltf-validator (${e.message}); run \`npm ci\` in ${path.dirname(new URL(import.meta.url).pathname)}`);
  process.exit(2);
}

const args = process.argv.slice(2);
const file = args.find((a) => !a.startsWith('--'));
if (!file) {
  console.error('usage: node validate_gltf.mjs FILE.glb|FILE.gltf [--json]');
  process.exit(2);
}

const severityName = ['error', 'warning', 'info', 'hint'];
const strict = args.includes('--strict');

// The glTF JSON of a .glb or .gltf (null when it cannot be parsed: the validator reports why).
function gltfJson(bytes) {
  try {
    const view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    if (bytes.length >= 20 && view.getUint32(0, true) === 0x46546c67) {
      const length = view.getUint32(12, true);
      return JSON.parse(new TextDecoder().decode(bytes.subarray(20, 20 + length)));
    }
    return JSON.parse(new TextDecoder().decode(bytes));
  } catch {
    return null;
  }
}

const splatSemantic = /^KHR_gaussian_splatting:(ROTATION|SCALE|OPACITY|SH_DEGREE_([0-3])_COEF_([0-9]))$/;

// True for MESH_PRIMITIVE_INVALID_ATTRIBUTE on a semantic that KHR_gaussian_splatting defines,
// on a primitive that carries the extension.
function isSplatSemanticIssue(message, doc) {
  if (strict || !doc || message.code !== 'MESH_PRIMITIVE_INVALID_ATTRIBUTE' || typeof message.pointer !== 'string') return false;
  const m = /^\/meshes\/(\d+)\/primitives\/(\d+)\/attributes\/(.*)$/.exec(message.pointer);
  if (!m) return false;
  const semantic = m[3].replace(/~1/g, '/').replace(/~0/g, '~');
  const s = splatSemantic.exec(semantic);
  if (!s || (s[2] !== undefined && Number(s[3]) > 2 * Number(s[2]))) return false;
  const primitive = doc.meshes?.[Number(m[1])]?.primitives?.[Number(m[2])];
  return Boolean(primitive?.extensions?.KHR_gaussian_splatting) && (doc.extensionsUsed ?? []).includes('KHR_gaussian_splatting');
}

try {
  const bytes = new Uint8Array(await readFile(file));
  const report = await validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 0,
    writeTimestamp: false,
    externalResourceFunction: async (uri) =>
      new Uint8Array(await readFile(path.resolve(path.dirname(file), decodeURIComponent(uri)))),
  });
  if (args.includes('--json')) console.log(JSON.stringify(report, null, 2));
  const issues = report.issues;
  const doc = gltfJson(bytes);
  const tolerated = issues.messages.filter((m) => m.severity === 0 && isSplatSemanticIssue(m, doc));
  const errors = issues.numErrors - tolerated.length;
  console.log(`${file}: glTF validator ${report.validatorVersion}: ${errors} errors, ` +
              `${issues.numWarnings} warnings, ${issues.numInfos} infos, ${issues.numHints} hints` +
              (tolerated.length ? ` (${tolerated.length} more tolerated: KHR_gaussian_splatting attribute semantics unknown to this validator)` : ''));
  for (const m of issues.messages) {
    const severity = tolerated.includes(m) ? 'tolerated' : (severityName[m.severity] ?? m.severity);
    console.log(`  ${severity} ${m.code} at ${m.pointer ?? m.offset ?? '-'}: ${m.message}`);
  }
  process.exit(errors > 0 ? 1 : 0);
} catch (e) {
  console.error(`${file}: validation failed: ${e}`);
  process.exit(2);
}
