#!/usr/bin/env python3
"""Writes a copy of a glTF whose buffers and images are data: URIs with each of them in a file of its own
beside it (NAME.bin, NAME1.bin, ...; NAME_image0.jpg, ...), as most exporters write glTF. The tests of
`bake --depfile` and of the cmake_bake sample use it to get a character with a .bin (CesiumMan's is embedded).

Usage: split_gltf.py IN.gltf OUT_DIR        (standard library only)
"""
import base64
import json
import os
import sys

EXT = {"image/jpeg": ".jpg", "image/png": ".png"}


def main():
    src, out_dir = sys.argv[1], sys.argv[2]
    name = os.path.splitext(os.path.basename(src))[0]
    with open(src) as f:
        gltf = json.load(f)
    os.makedirs(out_dir, exist_ok=True)
    for kind, items in (("buffer", gltf.get("buffers", [])), ("image", gltf.get("images", []))):
        for i, item in enumerate(items):
            uri = item.get("uri", "")
            if not uri.startswith("data:"):
                continue
            head, data = uri.split(",", 1)
            mime = head[5:].split(";")[0]
            if kind == "buffer":
                file = name + (str(i) if i else "") + ".bin"
            else:
                file = "%s_image%d%s" % (name, i, EXT.get(mime, ".bin"))
            with open(os.path.join(out_dir, file), "wb") as f:
                f.write(base64.b64decode(data))
            item["uri"] = file
    with open(os.path.join(out_dir, name + ".gltf"), "w") as f:
        json.dump(gltf, f, indent=1)


if __name__ == "__main__":
    main()
