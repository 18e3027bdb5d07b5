// A reader and writer of fsv-bench's sealed .npz archives in plain Node.js (no packages): the
// camera-input files a method reads and the estimates files it writes (docs/formats.md).
//
//   import { readNpz, writeNpz } from "./npz.mjs";
//   const { arrays, meta } = readNpz("inputs/lift-u0-g0-m0-s11.npz");
//   arrays["camera/depth_counts"]  ->  { dtype: "<u2", shape: [T, H, W], data: Uint16Array }
//   writeNpz("est/lift-u0-g0-m0-s11.npz", { "box/pos": { dtype: "<f8", shape: [T, 3], data } }, meta);

import { readFileSync, writeFileSync, renameSync } from "node:fs";
import { crc32, inflateRawSync } from "node:zlib";

const TYPED = {
  "<f8": Float64Array, "<f4": Float32Array, "<u2": Uint16Array, "<i8": BigInt64Array, "<i4": Int32Array,
  "|u1": Uint8Array, "|b1": Uint8Array, "|i1": Int8Array, "<u8": BigUint64Array,
};

/** Parses one .npy entry: its dtype, shape and data (a typed array over a copy of the bytes). */
export function parseNpy(buf) {
  if (buf.readUInt32BE(0) !== 0x934e554d || buf.toString("latin1", 4, 6) !== "PY") throw new Error("not an .npy entry");
  const major = buf[6];
  const headerLength = major === 1 ? buf.readUInt16LE(8) : buf.readUInt32LE(8);
  const start = major === 1 ? 10 : 12;
  const header = buf.toString("latin1", start, start + headerLength);
  const descr = /'descr':\s*'([^']+)'/.exec(header)[1];
  if (/'fortran_order':\s*True/.test(header)) throw new Error("Fortran-ordered arrays are not written by fsv-bench");
  const shape = /'shape':\s*\(([^)]*)\)/.exec(header)[1].split(",").map((s) => s.trim()).filter(Boolean).map(Number);
  const Kind = TYPED[descr];
  if (!Kind) throw new Error(`dtype ${descr} not handled`);
  const body = buf.subarray(start + headerLength);
  const copy = new Uint8Array(body.length);
  copy.set(body);
  return { dtype: descr, shape, data: new Kind(copy.buffer, 0, body.length / Kind.BYTES_PER_ELEMENT) };
}

/** Reads a zip of .npy entries; returns {arrays, meta} (meta: the parsed meta.json). */
export function readNpz(path) {
  const zip = readFileSync(path);
  let eocd = zip.length - 22;
  while (eocd >= 0 && zip.readUInt32LE(eocd) !== 0x06054b50) eocd--;
  if (eocd < 0) throw new Error(`${path}: not a zip archive`);
  let count = zip.readUInt16LE(eocd + 10);
  let offset = zip.readUInt32LE(eocd + 16);
  const arrays = {};
  let meta = null;
  if (offset === 0xffffffff || count === 0xffff) {  // zip64: the end-of-central-directory record before
    const locator = eocd - 20;
    const record = Number(zip.readBigUInt64LE(locator + 8));
    count = Number(zip.readBigUInt64LE(record + 32));
    offset = Number(zip.readBigUInt64LE(record + 48));
  }
  for (let i = 0; i < count; i++) {
    const method = zip.readUInt16LE(offset + 10);
    let compressed = zip.readUInt32LE(offset + 20);
    const nameLength = zip.readUInt16LE(offset + 28), extraLength = zip.readUInt16LE(offset + 30);
    const commentLength = zip.readUInt16LE(offset + 32);
    let local = zip.readUInt32LE(offset + 42);
    const name = zip.toString("utf8", offset + 46, offset + 46 + nameLength);
    // zip64 extra field (id 1): sizes and offset that did not fit
    let extra = offset + 46 + nameLength;
    const extraEnd = extra + extraLength;
    while (extra < extraEnd) {
      const id = zip.readUInt16LE(extra), size = zip.readUInt16LE(extra + 2);
      if (id === 1) {
        let p = extra + 4;
        if (zip.readUInt32LE(offset + 24) === 0xffffffff) p += 8;  // uncompressed size
        if (compressed === 0xffffffff) { compressed = Number(zip.readBigUInt64LE(p)); p += 8; }
        if (local === 0xffffffff) { local = Number(zip.readBigUInt64LE(p)); }
      }
      extra += 4 + size;
    }
    const dataStart = local + 30 + zip.readUInt16LE(local + 26) + zip.readUInt16LE(local + 28);
    const raw = zip.subarray(dataStart, dataStart + compressed);
    const bytes = method === 8 ? inflateRawSync(raw) : raw;
    const entry = parseNpy(Buffer.from(bytes));
    const key = name.replace(/\.npy$/, "");
    if (key === "meta.json") meta = JSON.parse(Buffer.from(entry.data).toString("utf8"));
    else arrays[key] = entry;
    offset += 46 + nameLength + extraLength + commentLength;
  }
  return { arrays, meta };
}

function npyBytes({ dtype, shape, data }) {
  const shapeText = shape.length === 1 ? `(${shape[0]},)` : `(${shape.join(", ")})`;
  let header = `{'descr': '${dtype}', 'fortran_order': False, 'shape': ${shapeText}, }`;
  const total = 10 + header.length + 1;
  header += " ".repeat((64 - (total % 64)) % 64) + "\n";
  const head = Buffer.alloc(10);
  head.writeUInt32BE(0x934e554d, 0);
  head.write("PY", 4, "latin1");
  head[6] = 1; head[7] = 0;
  head.writeUInt16LE(header.length, 8);
  return Buffer.concat([head, Buffer.from(header, "latin1"), Buffer.from(data.buffer, data.byteOffset, data.byteLength)]);
}

/** Writes {name: {dtype, shape, data}} and meta (as meta.json) to a stored zip; replaces path atomically. */
export function writeNpz(path, arrays, meta) {
  const entries = Object.entries(arrays).map(([name, a]) => [name, npyBytes(a)]);
  const metaBytes = Buffer.from(JSON.stringify(meta), "utf8");
  entries.push(["meta.json", npyBytes({ dtype: "|u1", shape: [metaBytes.length], data: new Uint8Array(metaBytes) })]);
  const parts = [], central = [];
  let offset = 0;
  for (const [key, body] of entries) {
    const name = Buffer.from(`${key}.npy`, "utf8");
    const crc = crc32(body) >>> 0;
    const local = Buffer.alloc(30);
    local.writeUInt32LE(0x04034b50, 0); local.writeUInt16LE(20, 4); local.writeUInt16LE(0, 8);  // stored
    local.writeUInt16LE(0, 10); local.writeUInt16LE(0x21, 12);  // 00:00, 1980-01-01: fixed, so equal content gives equal bytes
    local.writeUInt32LE(crc, 14); local.writeUInt32LE(body.length, 18); local.writeUInt32LE(body.length, 22);
    local.writeUInt16LE(name.length, 26); local.writeUInt16LE(0, 28);
    const dir = Buffer.alloc(46);
    dir.writeUInt32LE(0x02014b50, 0); dir.writeUInt16LE(20, 4); dir.writeUInt16LE(20, 6);
    dir.writeUInt16LE(0, 10); dir.writeUInt16LE(0, 12); dir.writeUInt16LE(0x21, 14);
    dir.writeUInt32LE(crc, 16); dir.writeUInt32LE(body.length, 20); dir.writeUInt32LE(body.length, 24);
    dir.writeUInt16LE(name.length, 28); dir.writeUInt32LE(offset, 42);
    parts.push(local, name, body);
    central.push(dir, name);
    offset += 30 + name.length + body.length;
  }
  const centralBytes = Buffer.concat(central);
  const end = Buffer.alloc(22);
  end.writeUInt32LE(0x06054b50, 0); end.writeUInt16LE(entries.length, 8); end.writeUInt16LE(entries.length, 10);
  end.writeUInt32LE(centralBytes.length, 12); end.writeUInt32LE(offset, 16);
  const tmp = `${path}.tmp-${process.pid}`;
  writeFileSync(tmp, Buffer.concat([...parts, centralBytes, end]));
  renameSync(tmp, path);
}
