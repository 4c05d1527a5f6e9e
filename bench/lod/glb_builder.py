"""A .glb written by hand (no lodkit, no glTF library): the bench scripts' inputs.

Accessors go into one buffer, each in a view of its own (4-byte aligned); write() adds the views,
accessors and buffer to the given glTF JSON and writes the GLB container.
"""
import json
import struct


class GlbBuilder:
    def __init__(self):
        self.chunks, self.views, self.accessors = [], [], []

    def accessor(self, data, count, kind, component, target=None, bounds=None):
        """The accessor's index. data: its bytes, tightly packed; target: the view's (34962 vertex
        data, 34963 indices); bounds: (min, max), which POSITION and animation inputs must have."""
        offset = sum(len(c) for c in self.chunks)
        self.chunks.append(data + b"\0" * (-len(data) % 4))
        view = {"buffer": 0, "byteOffset": offset, "byteLength": len(data)}
        if target:
            view["target"] = target
        self.views.append(view)
        a = {"bufferView": len(self.views) - 1, "componentType": component, "count": count, "type": kind}
        if bounds:
            a["min"], a["max"] = bounds
        self.accessors.append(a)
        return len(self.accessors) - 1

    def write(self, path, doc):
        doc["bufferViews"], doc["accessors"] = self.views, self.accessors
        binary = b"".join(self.chunks)
        doc["buffers"] = [{"byteLength": len(binary)}]
        text = json.dumps(doc, separators=(",", ":")).encode()
        text += b" " * (-len(text) % 4)
        with open(path, "wb") as f:
            f.write(struct.pack("<III", 0x46546C67, 2, 12 + 8 + len(text) + 8 + len(binary)))
            f.write(struct.pack("<II", len(text), 0x4E4F534A) + text)
            f.write(struct.pack("<II", len(binary), 0x004E4942) + binary)
