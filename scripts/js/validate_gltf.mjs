// Runs the Khronos glTF-Validator (npm `gltf-validator`) on each file named: prints one line
// per file (errors, warnings, infos) and the errors themselves, and exits 1 if any file has
// an error. Used by scripts/validate_gltf.sh.
import { readFile } from 'node:fs/promises';
import { createRequire } from 'node:module';
const require = createRequire(process.env.VALIDATOR_DIR + '/');
const validator = require('gltf-validator');

let failed = false;
for (const file of process.argv.slice(2)) {
  const bytes = new Uint8Array(await readFile(file));
  const report = await validator.validateBytes(bytes, { maxIssues: 50 });
  const i = report.issues;
  console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos`);
  for (const m of i.messages) {
    if (m.severity === 0 || process.env.VERBOSE) {
      console.log(`  ${['error', 'warning', 'info', 'hint'][m.severity]} ${m.code} ${m.pointer ?? ''}: ${m.message}`);
    }
  }
  if (i.numErrors > 0) failed = true;
}
process.exit(failed ? 1 : 0);
