// Test data for lodkit's own meshopt vertex decoder (src/io/meshopt_codec.cpp), made by an
// independent implementation: meshoptimizer's JavaScript encoder and decoder (npm, 1.3.0).
//
//   node meshopt_vectors.mjs vectors OUT.json
//     Streams of several kinds of data, strides and counts, encoded at codec versions 0 and 1 and
//     every level, each with its source bytes; and COLOR-filtered colours with what meshoptimizer's
//     decoder makes of them. Base64 throughout.
//   node meshopt_vectors.mjs khr IN.glb OUT.glb
//     A file lodkit wrote with -c (EXT_meshopt_compression, vertex codec version 0) as
//     KHR_meshopt_compression with every ATTRIBUTES view encoded again at version 1 (levels 0 to 3 in
//     turn): the same content, in the newer bitstream. Prints the streams' channel and control modes.
//   node meshopt_vectors.mjs ext IN.glb OUT.glb
//     The other way: a KHR_meshopt_compression file (lodkit's -c --meshopt-khr) decoded by
//     meshoptimizer and written as EXT_meshopt_compression at version 0.
//   node meshopt_vectors.mjs decode IN.json OUT.json
//     Decodes lodkit's own version 1 streams with meshoptimizer's decoder.
import { readFileSync, writeFileSync } from 'node:fs';
import { MeshoptEncoder, MeshoptDecoder } from 'meshoptimizer';

await MeshoptEncoder.ready;
await MeshoptDecoder.ready;

const b64 = (bytes) => Buffer.from(bytes.buffer, bytes.byteOffset, bytes.byteLength).toString('base64');

// A small deterministic generator (xorshift32): the vectors are the same on every run.
let state = 2463534242;
const next = () => {
	state ^= state << 13;
	state >>>= 0;
	state ^= state >>> 17;
	state ^= state << 5;
	state >>>= 0;
	return state;
};

// `count` elements of `stride` bytes of one kind of data.
function makeData(kind, count, stride) {
	const bytes = new Uint8Array(count * stride);
	const view = new DataView(bytes.buffer);
	for (let i = 0; i < count; i++)
		for (let k = 0; k < stride / 4; k++) {
			const at = i * stride + 4 * k;
			if (kind === 'smooth-float') view.setFloat32(at, Math.sin(0.01 * i + k) * (k + 1) * 10, true);
			else if (kind === 'random') view.setUint32(at, next(), true);
			else if (kind === 'constant') view.setUint32(at, 0xdeadbeef + k, true);
			else if (kind === 'shorts') {
				view.setUint16(at, (i * 37 + k * 1000) & 0xffff, true);
				view.setInt16(at + 2, Math.round(3000 * Math.cos(0.05 * i)), true);
			} else if (kind === 'sparse') view.setUint32(at, i % 97 === 0 ? next() : (i >> 6) + k, true);
			else if (kind === 'counter') view.setUint32(at, i * 4096 + k, true);
		}
	return bytes;
}

function vectors(out) {
	const streams = [];
	const kinds = ['smooth-float', 'random', 'constant', 'shorts', 'sparse', 'counter'];
	const strides = [4, 8, 12, 16, 24, 32, 64, 256];
	const counts = [1, 15, 17, 256, 257, 1000];
	let n = 0;
	for (const kind of kinds)
		for (const stride of strides)
			for (const count of counts) {
				// Every combination at version 1 (over the levels in turn) and at version 0.
				const data = makeData(kind, count, stride);
				const level = n % 4;
				streams.push({ kind, stride, count, version: 1, level, source: b64(data),
					encoded: b64(MeshoptEncoder.encodeVertexBufferLevel(data, count, stride, level, 1)) });
				streams.push({ kind, stride, count, version: 0, level: 0, source: b64(data),
					encoded: b64(MeshoptEncoder.encodeVertexBufferLevel(data, count, stride, 0, 0)) });
				n++;
			}
	// Colours through the COLOR filter at several precisions, then the codec; meshoptimizer's own
	// decoder says what they decode to.
	const colors = [];
	for (const [stride, bits] of [[4, 8], [4, 6], [8, 16], [8, 12], [8, 10]]) {
		const count = 300;
		const rgba = new Float32Array(count * 4);
		for (let i = 0; i < rgba.length; i++) rgba[i] = i % 4 === 3 ? (next() % 1001) / 1000 : (Math.sin(i * 0.37) + 1) / 2;
		const filtered = MeshoptEncoder.encodeFilterColor(rgba, count, stride, bits);
		const encoded = MeshoptEncoder.encodeVertexBufferLevel(filtered, count, stride, 2, 1);
		const decoded = new Uint8Array(count * stride);
		MeshoptDecoder.decodeVertexBuffer(decoded, count, stride, encoded, 'COLOR');
		colors.push({ stride, bits, count, encoded: b64(encoded), filtered: b64(filtered), decoded: b64(decoded) });
	}
	writeFileSync(out, JSON.stringify({ streams, colors }));
}

// GLB chunks: JSON and BIN.
function readGlb(path) {
	const file = readFileSync(path);
	if (file.readUInt32LE(0) !== 0x46546c67) throw new Error(`${path}: not a GLB`);
	let at = 12, json = null, bin = Buffer.alloc(0);
	while (at < file.length) {
		const length = file.readUInt32LE(at), type = file.readUInt32LE(at + 4);
		const chunk = file.subarray(at + 8, at + 8 + length);
		if (type === 0x4e4f534a) json = JSON.parse(chunk.toString('utf8'));
		else if (type === 0x004e4942) bin = chunk;
		at += 8 + length;
	}
	return { json, bin };
}

function writeGlb(path, json, bin) {
	const pad = (b, byte) => Buffer.concat([b, Buffer.alloc((4 - (b.length % 4)) % 4, byte)]);
	const text = pad(Buffer.from(JSON.stringify(json), 'utf8'), 0x20), data = pad(bin, 0);
	const header = Buffer.alloc(12);
	header.writeUInt32LE(0x46546c67, 0), header.writeUInt32LE(2, 4);
	header.writeUInt32LE(12 + 8 + text.length + (data.length ? 8 + data.length : 0), 8);
	const chunk = (type, body) => {
		const h = Buffer.alloc(8);
		h.writeUInt32LE(body.length, 0), h.writeUInt32LE(type, 4);
		return Buffer.concat([h, body]);
	};
	writeFileSync(path, Buffer.concat([header, chunk(0x4e4f534a, text), ...(data.length ? [chunk(0x004e4942, data)] : [])]));
}

// Every meshopt view of `input` decoded by meshoptimizer's decoder and encoded again, into `output`:
// to 'khr' (KHR_meshopt_compression, vertex streams at version 1, levels 0 to 3 in turn) or to 'ext'
// (EXT_meshopt_compression, version 0).
function recode(input, output, to) {
	const EXT = 'EXT_meshopt_compression', KHR = 'KHR_meshopt_compression';
	const [from, into, version] = to === 'khr' ? [EXT, KHR, 1] : [KHR, EXT, 0];
	const { json, bin } = readGlb(input);
	const parts = [];
	let size = 0, level = 0;
	const channelModes = {}, controlModes = [0, 0, 0, 0];
	const place = (bytes) => {
		const padding = (4 - (size % 4)) % 4;
		if (padding) parts.push(Buffer.alloc(padding)), (size += padding);
		const at = size;
		parts.push(Buffer.from(bytes.buffer, bytes.byteOffset, bytes.byteLength));
		size += bytes.byteLength;
		return at;
	};
	// Buffer 0 (the BIN chunk) in view order, each view's bytes placed anew.
	for (const view of json.bufferViews) {
		const ext = view.extensions && view.extensions[from];
		if (!ext) {
			if ((view.buffer ?? 0) === 0) view.byteOffset = place(bin.subarray(view.byteOffset ?? 0, (view.byteOffset ?? 0) + view.byteLength));
			continue;
		}
		let bytes = bin.subarray(ext.byteOffset ?? 0, (ext.byteOffset ?? 0) + ext.byteLength);
		if (ext.mode === 'ATTRIBUTES') {
			const raw = new Uint8Array(ext.count * ext.byteStride);
			MeshoptDecoder.decodeVertexBuffer(raw, ext.count, ext.byteStride, bytes);  // (unfiltered: lodkit writes no filters)
			bytes = MeshoptEncoder.encodeVertexBufferLevel(raw, ext.count, ext.byteStride, level, version);
			level = (level + 1) % 4;
			if (version === 1) {
				// What the stream uses: the tail's channel modes, and the first block's control modes.
				const tail = bytes.subarray(bytes.length - ext.byteStride / 4);
				for (const mode of tail) channelModes[mode] = (channelModes[mode] || 0) + 1;
				const control = bytes.subarray(1, 1 + ext.byteStride / 4);
				for (let k = 0; k < ext.byteStride; k++) controlModes[(control[k >> 2] >> (2 * (k & 3))) & 3]++;
			}
		}
		ext.byteOffset = place(bytes);
		ext.byteLength = bytes.byteLength;
		view.extensions = { [into]: ext };
	}
	for (const buffer of json.buffers)
		if (buffer.extensions && buffer.extensions[from]) buffer.extensions = { [into]: buffer.extensions[from] };
	json.buffers[0].byteLength = size;
	for (const list of ['extensionsUsed', 'extensionsRequired'])
		if (json[list]) json[list] = json[list].map((e) => (e === from ? into : e));
	writeGlb(output, json, Buffer.concat(parts));
	console.log(JSON.stringify({ channelModes, controlModes }));
}

// Decodes streams another encoder made: [{count, stride, encoded}] in, [decoded] out (base64; null
// where meshoptimizer's decoder refuses the stream).
function decode(input, output) {
	const streams = JSON.parse(readFileSync(input, 'utf8'));
	const out = streams.map(({ count, stride, encoded }) => {
		const target = new Uint8Array(count * stride);
		try {
			MeshoptDecoder.decodeVertexBuffer(target, count, stride, new Uint8Array(Buffer.from(encoded, 'base64')));
		} catch {
			return null;
		}
		return b64(target);
	});
	writeFileSync(output, JSON.stringify(out));
}

const [command, ...args] = process.argv.slice(2);
if (command === 'vectors' && args.length === 1) vectors(args[0]);
else if ((command === 'khr' || command === 'ext') && args.length === 2) recode(args[0], args[1], command);
else if (command === 'decode' && args.length === 2) decode(args[0], args[1]);
else {
	console.error('usage: node meshopt_vectors.mjs vectors OUT.json | khr IN.glb OUT.glb | ext IN.glb OUT.glb | decode IN.json OUT.json');
	process.exit(2);
}
