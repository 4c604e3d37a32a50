// Validates Kubernetes manifests against the Kubernetes API's OpenAPI schemas
// (npm: kubernetes-models, whose models validate with ajv against the schemas
// generated from the Kubernetes OpenAPI spec), offline.
//
//   node tests/deploy/validate_k8s.mjs deploy/k8s/*.yaml
//
// Needs `npm install` in tests/deploy/ (package.json there). Exits 0 when
// every document is valid, 1 with one line per error otherwise.
// kustomization.yaml is not an API object and is skipped.
import { readFileSync } from "node:fs";
import { parseAllDocuments } from "yaml";

let errors = 0;
let checked = 0;
for (const file of process.argv.slice(2)) {
  const docs = parseAllDocuments(readFileSync(file, "utf8"));
  for (const doc of docs) {
    if (doc.errors.length > 0) {
      console.error(`${file}: YAML: ${doc.errors[0].message}`);
      errors++;
      continue;
    }
    const obj = doc.toJS();
    if (obj === null) continue;
    if (obj.kind === "Kustomization") continue;
    const { apiVersion, kind } = obj;
    if (typeof apiVersion !== "string" || typeof kind !== "string") {
      console.error(`${file}: a document without apiVersion and kind`);
      errors++;
      continue;
    }
    let Model;
    try {
      const module = await import(`kubernetes-models/${apiVersion}/${kind}`);
      Model = module[kind];
    } catch (e) {
      console.error(`${file}: unknown kind ${apiVersion} ${kind}`);
      errors++;
      continue;
    }
    try {
      new Model(obj).validate();
      checked++;
      console.log(`${file}: ${apiVersion} ${kind} ${obj.metadata?.name}: valid`);
    } catch (e) {
      console.error(`${file}: ${apiVersion} ${kind} ${obj.metadata?.name}: ${e.message}`);
      errors++;
    }
  }
}
console.log(`${checked} valid, ${errors} errors`);
process.exit(errors === 0 && checked > 0 ? 0 : 1);
