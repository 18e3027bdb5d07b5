// A whole (trivial) method in Node.js through files: for every episode that `fsv-bench export` wrote,
// read its camera inputs and write an estimates file: the box held at its first-frame pose, no
// contacts, zero kinematics. `fsv-bench score` then scores the folder like any method's.
//
//   fsv-bench export --suite smoke --out runs/inputs
//   node examples/js/static_method.mjs runs/inputs runs/estimates
//   fsv-bench score --suite smoke --estimates runs/estimates --out runs/scores
//
// It prints one line per episode: the name, the frames and the sum of the depth in metres (a check
// that the depth was read as the benchmark wrote it), and, where the file holds the colour stream
// (`fsv-bench export --streams depth,colour`), its size and the mean of each of its channels.

import { mkdirSync, readFileSync } from "node:fs";
import { join } from "node:path";
import { readNpz, writeNpz } from "./npz.mjs";

const [inputs, out] = process.argv.slice(2);
if (!inputs || !out) {
  console.error("usage: node static_method.mjs INPUTS_DIR OUT_DIR");
  process.exit(2);
}
mkdirSync(out, { recursive: true });
const suite = JSON.parse(readFileSync(join(inputs, "suite.json"), "utf8"));
for (const ep of suite.episodes) {
  const { arrays, meta } = readNpz(join(inputs, ep.file));
  const counts = arrays["camera/depth_counts"], quantum = arrays["camera/depth_quantum_m"].data[0];
  const [T] = counts.shape;
  let depthSum = 0;
  for (const c of counts.data) depthSum += c * quantum;
  const K = meta.hand.finger_names.length;
  const pos = new Float64Array(T * 3), rot = new Float64Array(T * 9);
  for (let t = 0; t < T; t++) {
    pos.set(arrays["init/box_pos"].data, 3 * t);
    rot.set(arrays["init/box_rot"].data, 9 * t);
  }
  const zeros3 = { dtype: "<f8", shape: [T, 3], data: new Float64Array(T * 3) };
  writeNpz(join(out, ep.file), {
    "box/pos": { dtype: "<f8", shape: [T, 3], data: pos },
    "box/rot": { dtype: "<f8", shape: [T, 3, 3], data: rot },
    "contacts/active": { dtype: "|b1", shape: [T, K], data: new Uint8Array(T * K) },
    "contacts/sliding": { dtype: "|b1", shape: [T, K], data: new Uint8Array(T * K) },
    "contacts/point": { dtype: "<f8", shape: [T, K, 3], data: new Float64Array(T * K * 3) },
    "contacts/normal": { dtype: "<f8", shape: [T, K, 3], data: new Float64Array(T * K * 3) },
    "kinematics/vel": zeros3, "kinematics/acc": zeros3, "kinematics/omega": zeros3, "kinematics/alpha": zeros3,
    "kinematics/valid": { dtype: "|b1", shape: [T], data: new Uint8Array(T).fill(1) },
  }, {
    format: "fsv-bench-estimates", version: 1, episode: meta.episode, suite: meta.suite, world: meta.world,
    finger_names: meta.hand.finger_names, method: "static box (Node.js example)", stages: { tracker: "static box" },
  });
  let colour = "";
  const rgb = arrays["colour/rgb"];
  if (rgb) {  // (T, H, W, 3) uint8, sRGB; its own calibration in colour/calib_*
    const sums = [0, 0, 0];
    for (let i = 0; i < rgb.data.length; i++) sums[i % 3] += rgb.data[i];
    const n = rgb.data.length / 3;
    colour = ` colour ${rgb.shape[2]}x${rgb.shape[1]} ${sums.map((s) => (s / n).toFixed(4)).join(" ")}`;
  }
  console.log(`${meta.episode} ${T} ${depthSum.toFixed(6)}${colour}`);
}
