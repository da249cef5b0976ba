"""Record what MeshLab (pymeshlab) reads from the third-party test meshes.

    python3 scripts/compare/meshlab_counts.py [ASSETS_THIRD_PARTY_DIR] > fixtures/third-party-meshes.json

For every PLY/OBJ under the folder (default: the one scripts/fetch-assets fills), the vertex and
face counts pymeshlab loads, or that it refused the file. `crates/mesh-core/tests/third_party_meshes.rs`
checks surfcap's readers against this table. Each file is loaded in its own process: pymeshlab can
crash on a malformed file. Needs `pip install pymeshlab`.
"""
import importlib.metadata, json, os, subprocess, sys

LOAD = """
import sys, pymeshlab
ms = pymeshlab.MeshSet()
try:
    ms.load_new_mesh(sys.argv[1])
except Exception:
    print("refused"); sys.exit(0)
m = ms.current_mesh()
print(m.vertex_number(), m.face_number(), flush=True)
"""

def main():
    cache = os.environ.get("SURFCAP_CACHE") or os.path.join(os.environ["HOME"], ".cache/surfcap")
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(cache, "assets/third-party")
    table = {}
    for d, _, files in sorted(os.walk(root)):
        for f in sorted(files):
            if not f.lower().endswith((".ply", ".obj")):
                continue
            path = os.path.join(d, f)
            rel = os.path.relpath(path, root)
            r = subprocess.run([sys.executable, "-c", LOAD, path], capture_output=True, text=True, timeout=120)
            words = r.stdout.split()
            # pymeshlab may crash while exiting after a load (it does after malformed.obj): the
            # counts printed before count.
            if len(words) == 2 and all(w.isdigit() for w in words):
                table[rel] = {"vertices": int(words[0]), "faces": int(words[1])}
            else:
                table[rel] = {"refused": True}
    json.dump({"reader": "pymeshlab " + importlib.metadata.version("pymeshlab"), "meshes": dict(sorted(table.items()))},
              sys.stdout, indent=1)
    print()

if __name__ == "__main__":
    main()
