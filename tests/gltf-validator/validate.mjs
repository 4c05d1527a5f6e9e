// Runs the Khronos glTF validator on each file given on the command line.
// Prints one line per file ("<path>: <n> errors, <m> warnings") followed by the errors and warnings,
// and exits with 1 if any file has an error (2 if a file cannot be read or validated at all).
//
//   node tests/gltf-validator/validate.mjs out.glb scene.gltf
import { readFile } from 'node:fs/promises';
import path from 'node:path';
import { createRequire } from 'node:module';

const require = createRequire(import.meta.url);
const validator = require('gltf-validator');

const files = process.argv.slice(2);
if (files.length === 0) {
  console.error('usage: node validate.mjs FILE.gltf|FILE.glb ...');
  process.exit(2);
}

let exitCode = 0;
for (const file of files) {
  let report;
  try {
    const bytes = await readFile(file);
    report = await validator.validateBytes(new Uint8Array(bytes), {
      uri: path.basename(file),
      maxIssues: 0,  // unlimited: the count must be exact
      writeTimestamp: false,
      // External buffers and images resolve next to the file, as a viewer would load them.
      externalResourceFunction: async (uri) =>
        new Uint8Array(await readFile(path.resolve(path.dirname(file), decodeURIComponent(uri)))),
    });
  } catch (error) {
    console.log(`${file}: cannot validate: ${error}`);
    exitCode = 2;
    continue;
  }
  const { numErrors, numWarnings, messages } = report.issues;
  console.log(`${file}: ${numErrors} errors, ${numWarnings} warnings`);
  for (const message of messages) {
    const severity = ['error', 'warning', 'info', 'hint'][message.severity] ?? 'issue';
    if (message.severity <= 1) console.log(`  ${severity} ${message.code} at ${message.pointer ?? ''}: ${message.message}`);
  }
  if (numErrors > 0 && exitCode === 0) exitCode = 1;
}
process.exit(exitCode);
