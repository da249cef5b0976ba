// Runs the Khronos glTF validator (npm gltf-validator) on .glb files.
//   node validate.mjs a.glb [b.glb ...]
// Prints one JSON line per file: {file, errors, warnings, infos, hints, messages}
// and exits 1 when any file has errors (or cannot be read), 0 otherwise.
import { readFile } from 'node:fs/promises';
import { validateBytes, version } from 'gltf-validator';

const files = process.argv.slice(2);
if (files.length === 0) {
  console.error('usage: node validate.mjs FILE.glb...');
  process.exit(2);
}
let failed = false;
for (const file of files) {
  try {
    const bytes = new Uint8Array(await readFile(file));
    const report = await validateBytes(bytes, { maxIssues: 50 });
    const i = report.issues;
    const messages = i.messages.map((m) => `${['error', 'warning', 'info', 'hint'][m.severity]} ${m.code} ${m.pointer ?? ''}: ${m.message}`);
    console.log(JSON.stringify({ file, validator: version(), errors: i.numErrors, warnings: i.numWarnings, infos: i.numInfos, hints: i.numHints, messages }));
    if (i.numErrors > 0) failed = true;
  } catch (e) {
    console.log(JSON.stringify({ file, errors: 1, messages: [`cannot validate: ${e}`] }));
    failed = true;
  }
}
process.exit(failed ? 1 : 0);
