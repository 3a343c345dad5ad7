// Runs the Khronos glTF validator (npm package gltf-validator, found through NODE_PATH) on one .gltf or
// .glb file, resolving its external files beside it, and prints the report's summary and messages as JSON.
const fs = require("fs");
const path = require("path");
const validator = require("gltf-validator");

const file = process.argv[2];
const bytes = new Uint8Array(fs.readFileSync(file));
validator
    .validateBytes(bytes, {
        uri: path.basename(file),
        maxIssues: 100,
        externalResourceFunction: (uri) =>
            new Promise((resolve, reject) => {
                const beside = path.resolve(path.dirname(file), decodeURIComponent(uri));
                fs.readFile(beside, (err, data) => (err ? reject(err.toString()) : resolve(new Uint8Array(data))));
            }),
    })
    .then((report) => {
        const { numErrors, numWarnings, numInfos, numHints, messages } = report.issues;
        console.log(JSON.stringify({ numErrors, numWarnings, numInfos, numHints, messages }));
    })
    .catch((error) => {
        console.error(String(error));
        process.exit(1);
    });
