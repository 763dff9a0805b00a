#!/usr/bin/env python3
"""ctest schema.*: `simreel schema` is a valid draft 2020-12 schema, every demo scene validates
against it, and it rejects a sample of what the loader rejects (each sample is checked against
`simreel validate` too, so the two agree). Usage: schema_test.py SIMREEL SOURCE_DIR"""
import copy, glob, json, os, subprocess, sys

import jsonschema

simreel, source = sys.argv[1], sys.argv[2]
schema = json.loads(subprocess.run([simreel, "schema"], check=True, capture_output=True, text=True).stdout)
jsonschema.Draft202012Validator.check_schema(schema)
validator = jsonschema.Draft202012Validator(schema)
failures = []

# The copy editors are pointed at (README "JSON Schema for editors") is the current schema.
with open(os.path.join(source, "docs/scene.schema.json")) as f:
    if json.load(f) != schema:
        failures.append("docs/scene.schema.json is stale: run simreel schema -o docs/scene.schema.json")

scenes = sorted(glob.glob(os.path.join(source, "demos/scenes/*.json")) +
                glob.glob(os.path.join(source, "docs/examples/*.json")))
assert scenes, "no demo scenes"
for path in scenes:
    with open(path) as f:
        scene = json.load(f)
    errors = sorted(validator.iter_errors(scene), key=lambda e: list(e.path))
    for e in errors[:3]:
        failures.append(f"{os.path.basename(path)}: /{'/'.join(map(str, e.path))}: {e.message[:200]}")

base = {"$schema": "scene.schema.json", "frames": 2,
        "colliders": [{"type": "plane"}],
        "emitters": [{"name": "a", "rate": 10}, {"effect": "smoke"}]}
bad = {  # what the loader rejects, one mistake each
    "unknown top-level key": lambda s: s.update(fsp=30),
    "wrong type": lambda s: s.update(fps="fast"),
    "out of range (exclusive minimum)": lambda s: s.update(fps=0),
    "out of range (maximum)": lambda s: s.update(render={"msaa": 99}),
    "unknown enum value": lambda s: s["colliders"][0].update(type="cone"),
    "unknown emitter key": lambda s: s["emitters"][0].update(rat=10),
    "negative rate": lambda s: s["emitters"][0].update(rate=-1),
    "bad color": lambda s: s["emitters"][0].update(color=[1, 2, 0]),
    "bad distribution": lambda s: s["emitters"][0].update(lifetime={"mean": 1, "spread": 2}),
    "unknown effect": lambda s: s["emitters"][1].update(effect="smok"),
    "unknown knob": lambda s: s["emitters"][1].update(densty=1),
    "emitter key on a preset": lambda s: s["emitters"][1].update(rate=100),
    "unknown nested key": lambda s: s.update(simulation={"max_stepp": 0.01}),
    "array item of the wrong kind": lambda s: s.update(cloths=[3]),
}

def loader_accepts(doc, name):
    path = os.path.join(os.environ.get("TMPDIR", "/tmp"), f"simreel-schema-{os.getpid()}.json")
    with open(path, "w") as f:
        json.dump(doc, f)
    try:
        return subprocess.run([simreel, "validate", path], capture_output=True).returncode == 0
    finally:
        os.remove(path)

if not validator.is_valid(base):
    failures.append("the base sample does not validate: " + str(next(validator.iter_errors(base)).message))
if not loader_accepts(base, "base"):
    failures.append("the loader rejects the base sample")
for name, change in bad.items():
    doc = copy.deepcopy(base)
    change(doc)
    if validator.is_valid(doc):
        failures.append(f"schema accepts: {name}")
    if loader_accepts(doc, name):
        failures.append(f"loader accepts (the sample is wrong): {name}")

for f in failures:
    print("FAIL", f)
print(f"{len(scenes)} demo scenes, {len(bad)} rejected samples, {len(failures)} failures")
sys.exit(1 if failures else 0)
