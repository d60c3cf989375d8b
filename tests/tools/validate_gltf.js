#!/usr/bin/env node
// Validates glTF 2.0 files with the Khronos glTF validator (npm package gltf-validator,
// installed here by `npm ci`). Prints each file's error/warning/info counts and every error
// and warning; exits 1 if any file has an error (or cannot be read), 0 otherwise.
// Usage: node validate_gltf.js FILE.glb|FILE.gltf ...
'use strict';
const fs = require('fs');
const path = require('path');
const validator = require('gltf-validator');

async function validate(file) {
  const bytes = new Uint8Array(fs.readFileSync(file));
  const report = await validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 0,  // report every issue
    externalResourceFunction: (uri) =>
      new Promise((resolve, reject) => {
        fs.readFile(path.resolve(path.dirname(file), decodeURIComponent(uri)), (err, data) =>
          err ? reject(err.toString()) : resolve(new Uint8Array(data)));
      }),
  });
  const issues = report.issues;
  console.log(`${file}: ${issues.numErrors} errors, ${issues.numWarnings} warnings, ` +
              `${issues.numInfos} infos, ${issues.numHints} hints`);
  for (const m of issues.messages) {
    if (m.severity <= 1) {  // 0 error, 1 warning
      console.log(`  ${m.severity === 0 ? 'error' : 'warning'} ${m.code} at ${m.pointer || '-'}: ${m.message}`);
    }
  }
  return issues.numErrors;
}

(async () => {
  const files = process.argv.slice(2);
  if (files.length === 0) {
    console.error('usage: node validate_gltf.js FILE...');
    process.exit(2);
  }
  let errors = 0;
  for (const file of files) {
    try {
      errors += await validate(file);
    } catch (e) {
      console.log(`${file}: cannot validate: ${e}`);
      errors += 1;
    }
  }
  process.exit(errors > 0 ? 1 : 0);
})();
