#!/usr/bin/env python3
"""predict-wall.py WORK [--nodes 1,2,4,8,16,64] [--tick 1.0,3.0] [--task-start S] [--submit S] [--local S]

The wall time of a cluster bake on N nodes, predicted from the units one submission of it
ran (WORK: the job's .voxlight-slurm folder: plan.json, each unit's unit.json, the merge's
summary.json). The model:

  * a node runs one unit at a time (units are submitted with --cpus-per-task = the node's
    cores), a unit takes its measured wall time (unit.json wall_seconds) plus a start-up cost
    (--task-start: Slurm launching the task and voxlight starting);
  * the job reaches Slurm --submit seconds after the command starts (planning: loading each
    scene, generating lightmap UVs where the bake will);
  * Slurm starts units only at its scheduling passes, every --tick seconds (1 s on the tuned
    test cluster, about 3 s with Slurm's defaults: docs/cluster-design.md section 6): a
    unit starts at the first pass at which what it depends on has ended (its scene's voxel
    unit, for a receiver; every unit, for the merge) and a node is free, in submission order;
  * the merge then takes the sum of its scenes' merge times (summary.json merge_seconds).

Prints, per tick, the wall time on each node count and with a node for every unit, and the
speed-up over the local bake (--local: its seconds; default the sum of the units and the
merge, as one process would spend them).
"""
import argparse, heapq, json, math, os, sys


def load(work):
    plan = json.load(open(os.path.join(work, "plan.json")))
    summary = json.load(open(os.path.join(work, "summary.json")))
    scenes = []
    for k, scene in enumerate(plan["scenes"]):
        folder = os.path.join(work, f"scene-{k}")
        units = scene["units"]
        names = ["voxel"] + [f"atlas-{a}-band-{b}-of-{atlas['bands']}"
                             for a, atlas in enumerate(units["atlases"]) for b in range(atlas["bands"])] + \
                [f"camera-{c}" for c in range(units["cameras"])]
        times = []
        for name in names:
            record = json.load(open(os.path.join(folder, name, "unit.json")))
            if not record["ok"]:
                sys.exit(f"{folder}/{name}: the unit failed: {record['error']}")
            times.append(record.get("wall_seconds", record["seconds"]))
        scenes.append({"scene": os.path.basename(scene["scene"]), "voxel": times[0], "receivers": times[1:],
                       "merge": summary["scenes"][k].get("merge_seconds", 0.0)})
    return scenes


def on_tick(t, tick):
    """The first scheduling pass at or after t."""
    return math.ceil(t / tick - 1e-9) * tick


def simulate(scenes, nodes, tick, start, submit):
    """Wall seconds of the job on `nodes` nodes: every unit starts at the first scheduling pass
    (every `tick` seconds) at which what it depends on has ended and a node is free, then takes
    `start` (Slurm launching it, voxlight starting) and its measured time."""
    free = [0.0] * nodes  # when each node is next free
    heapq.heapify(free)
    # Voxel units first, in scene order, then every receiver in the order its voxel unit ends
    # (arrays submitted per scene; a pass starts the eligible ones in submission order).
    voxel_end = []
    for s in scenes:
        begin = on_tick(max(submit, heapq.heappop(free)), tick)
        end = begin + start + s["voxel"]
        heapq.heappush(free, end)
        voxel_end.append(end)
    pending = sorted((voxel_end[k], k, r, seconds)
                     for k, s in enumerate(scenes) for r, seconds in enumerate(s["receivers"]))
    last = max(voxel_end)
    for ready, k, r, seconds in pending:
        begin = on_tick(max(ready, heapq.heappop(free)), tick)
        end = begin + start + seconds
        heapq.heappush(free, end)
        last = max(last, end)
    merge = sum(s["merge"] for s in scenes)
    return on_tick(last, tick) + start + merge


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("work")
    ap.add_argument("--nodes", default="1,2,4,8,16,64")
    ap.add_argument("--tick", default="1.0,3.0")
    ap.add_argument("--task-start", type=float, default=0.1)
    ap.add_argument("--submit", type=float, default=1.0)
    ap.add_argument("--local", type=float, default=None)
    a = ap.parse_args()
    scenes = load(a.work)
    nodes = [int(n) for n in a.nodes.split(",")]
    units = sum(1 + len(s["receivers"]) for s in scenes)
    work = sum(s["voxel"] + sum(s["receivers"]) for s in scenes)
    merge = sum(s["merge"] for s in scenes)
    local = a.local if a.local is not None else work + merge
    print(f"{len(scenes)} scene(s), {units} units: {work:.2f} s of unit work, merge {merge:.2f} s; local bake {local:.2f} s")
    for s in scenes:
        rec = ", ".join(f"{t:.2f}" for t in s["receivers"])
        print(f"  {s['scene']}: voxel {s['voxel']:.2f} s, receivers [{rec}] s, merge {s['merge']:.2f} s")
    print("| pass every | " + " | ".join(f"{n} node{'s' if n > 1 else ''}" for n in nodes) + " | unlimited nodes |")
    print("|---|" + "---:|" * (len(nodes) + 1))
    for tick in (float(t) for t in a.tick.split(",")):
        cells = []
        for n in list(nodes) + [units]:
            wall = simulate(scenes, n, tick, a.task_start, a.submit)
            cells.append(f"{wall:.1f} s ({local / wall:.2f}x)")
        print(f"| {tick:g} s | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
