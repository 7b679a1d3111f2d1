#!/usr/bin/env python3
"""Writes the SI twin (m, rad, kg, s, N) of a mechanism file declared in mm and deg.

The twin is the same mechanism: every number converted by hand-written rules below (lengths
x 1e-3, angles x pi/180, inertia kg*mm^2 x 1e-6, g mm/s^2 x 1e-3, torques N*mm x 1e-3, table keys by
their measure's unit). Tests run both files and compare the outputs converted (issue 11: "the same
mechanism written in mm/deg and in m/rad must give the same results converted").

    python3 tests/data/units/gen_si_twin.py mechanisms/crank-rocker.yaml tests/data/units/crank-rocker-si.yaml
    python3 tests/data/units/gen_si_twin.py tests/data/units/press.yaml tests/data/units/press-si.yaml
"""
import math
import sys

import yaml

MM = 1e-3
DEG = math.pi / 180.0


def main(src, dst):
    with open(src) as f:
        doc = yaml.safe_load(f)
    u = doc.get("units", {})
    assert u.get("length") == "mm" and u.get("angle") == "deg", "expects a mm/deg file"
    assert u.get("mass", "kg") == "kg" and u.get("time", "s") == "s" and u.get("force", "N") == "N"
    doc["units"] = {"length": "m", "angle": "rad", "mass": "kg", "time": "s", "force": "N"}
    lin = lambda v: [x * MM for x in v]
    ground = doc.get("ground", {})
    if "points" in ground:
        ground["points"] = {k: lin(v) for k, v in ground["points"].items()}
    kinds = {}
    for b in doc["bodies"]:
        if "inertia" in b:
            b["inertia"] = b["inertia"] * MM * MM
        if "com" in b:
            b["com"] = lin(b["com"])
        p = b["pose"]
        b["pose"] = [p[0] * MM, p[1] * MM] + ([p[2] * DEG] if len(p) > 2 else [])
        if "points" in b:
            b["points"] = {k: lin(v) for k, v in b["points"].items()}
        if "outline" in b:
            b["outline"] = [lin(v) for v in b["outline"]]
    for j in doc.get("joints", []):
        kinds[j["name"]] = j["type"]
        if "limits" in j:
            f = DEG if j["type"] == "revolute" else MM
            j["limits"] = [x * f for x in j["limits"]]
        if "angle" in j:
            j["angle"] = j["angle"] * DEG
        if "length" in j:
            j["length"] = j["length"] * MM
    measure_unit = {}
    for m in doc.get("measures", []):
        angular = m["type"] == "angle" or (m["type"] == "joint" and kinds[m["joint"]] == "revolute")
        measure_unit[m["name"]] = DEG if angular else MM
    for l in doc.get("loads", []):
        if l["type"] == "gravity" and "g" in l:
            l["g"] = lin(l["g"])
        if l["type"] == "torque":
            l["torque"] = l["torque"] * MM
        if "table" in l:
            f = measure_unit[l["table"]["measure"]]
            l["table"]["points"] = [[x * f, y] for x, y in l["table"]["points"]]
        assert l["type"] in ("gravity", "force", "torque"), "rule missing for " + l["type"]
    for d in doc.get("drivers", []):
        assert "initial" not in d and d.get("profile", "constant-speed") == "constant-speed"
        assert isinstance(d["speed"], str), "speed with a unit (e.g. 300 rpm) stays as it is"
    for p in doc.get("design_positions", []):
        p["inputs"] = {k: v * (DEG if kinds[k] == "revolute" else MM) for k, v in p["inputs"].items()}
        t = p.get("target")
        if t:
            t["at"] = lin(t["at"])
            if "angle" in t:
                t["angle"] = t["angle"] * DEG
            if "tolerance" in t:
                t["tolerance"] = t["tolerance"] * MM
    with open(dst, "w") as f:
        f.write("# SI twin of %s, written by tests/data/units/gen_si_twin.py (do not edit).\n" % src)
        f.write("# The same mechanism in m, rad, kg, s, N: every output must equal the mm/deg\n")
        f.write("# file's converted (tests/unit/cli/common_trust_cli_test.cpp).\n")
        yaml.safe_dump(doc, f, sort_keys=False, default_flow_style=None, width=100)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])
