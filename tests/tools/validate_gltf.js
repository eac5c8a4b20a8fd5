// Validates binary glTF files with the Khronos glTF validator (npm gltf-validator, installed by
// scripts/setup.sh test into build/tools): one line per file, "<file>: errors E, warnings W, infos I",
// then every error and warning with its code and pointer. Exits 1 when any file has an error.
//   node tests/tools/validate_gltf.js build/tools/node_modules FILE.glb...
"use strict";
const fs = require("fs");
const path = require("path");
const validator = require(path.resolve(process.argv[2], "gltf-validator"));

async function main() {
  let failed = false;
  for (const file of process.argv.slice(3)) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {
      uri: path.basename(file),
      maxIssues: 100,
      // Extensions the validator does not know (EXT_mesh_features, EXT_structural_metadata) are
      // reported as infos, not errors, and so are the buffer views only they use (UNUSED_OBJECT):
      // their checks are the test's.
    });
    const i = report.issues;
    console.log(`${file}: errors ${i.numErrors}, warnings ${i.numWarnings}, infos ${i.numInfos}, hints ${i.numHints}`);
    for (const m of i.messages)
      if (m.severity <= 1) console.log(`  ${m.severity === 0 ? "error" : "warning"} ${m.code} ${m.pointer || ""}: ${m.message}`);
      else if (m.code === "UNSUPPORTED_EXTENSION") console.log(`  info ${m.code} ${m.pointer || ""}: ${m.message}`);
    failed = failed || i.numErrors > 0;
  }
  process.exit(failed ? 1 : 0);
}
main().catch((e) => { console.error(e); process.exit(2); });
