#!/usr/bin/env node
// Validates glTF files with the Khronos glTF validator; prints a one-line summary per file
// and exits 1 when any has errors.
const fs = require('fs');
const path = require('path');
// The Khronos validator's npm package (2.0.0-dev.3.10, Apache-2.0: vendor/gltf-validator/LICENSE),
// kept in the repository so the tests need no network, only node.
const validator = require('./vendor/gltf-validator');
(async () => {
  let failed = false;
  for (const file of process.argv.slice(2)) {
    const data = new Uint8Array(fs.readFileSync(file));
    const report = await validator.validateBytes(data, {
      uri: path.basename(file),
      externalResourceFunction: (uri) => new Promise((resolve, reject) => {
        try { resolve(new Uint8Array(fs.readFileSync(path.resolve(path.dirname(file), decodeURIComponent(uri))))); }
        catch (e) { reject(e.toString()); }
      }),
    });
    const i = report.issues;
    console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos`);
    for (const m of i.messages) if (m.severity <= 1) console.log(`  ${m.severity === 0 ? 'error' : 'warning'} ${m.code} ${m.pointer || ''}: ${m.message}`);
    if (i.numErrors > 0) failed = true;
  }
  process.exit(failed ? 1 : 0);
})();
