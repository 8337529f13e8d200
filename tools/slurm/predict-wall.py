#!/usr/bin/env python3
"""predict-wall.py WORK [--nodes 1,2,4,8,16,64] [--hop 1.0,3.0] [--task-start S] [--local S]

The wall time of a cluster bake on N nodes, predicted from the units one submission of it
ran (WORK: the job's .voxlight-slurm folder: plan.json, each unit's unit.json, the merge's
summary.json). The model:

  * a node runs one unit at a time (units are submitted with --cpus-per-task = the node's
    cores), a unit takes its measured wall time (unit.json wall_seconds) plus a start-up cost
    (--task-start: Slurm launching the task and voxlight starting);
  * a unit becomes eligible one scheduling hop (--hop) after what it depends on ended:
    submission for the voxel units, its scene's voxel unit for a receiver, every unit for the
    merge; eligible units start in submission order on the first free node;
  * the merge then takes the sum of its scenes' merge times (summary.json merge_seconds).

Prints, per hop, the wall time on each node count, the speed-up over the local bake (--local:
its seconds; default the sum of the units and the merge, one process), and the critical path
(hop + slowest voxel unit + hop + slowest receiver after it + hop + merge) that no number of
nodes goes below.
"""
import argparse, heapq, json, os, sys


def load(work):
    plan = json.load(open(os.path.join(work, "plan.json")))
    summary = json.load(open(os.path.join(work, "summary.json")))
    scenes = []
    for k, scene in enumerate(plan["scenes"]):
        folder = os.path.join(work, f"scene-{k}")
        units = scene["units"]
        names = ["voxel"] + [f"lightmap-{b}-of-{units['bands']}" for b in range(units["bands"])] + \
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


def simulate(scenes, nodes, hop, start):
    free = [0.0] * nodes  # when each node is next free
    heapq.heapify(free)
    # Voxel units: eligible after one hop, in scene order.
    voxel_end = []
    for s in scenes:
        begin = max(hop, heapq.heappop(free))
        end = begin + start + s["voxel"]
        heapq.heappush(free, end)
        voxel_end.append(end)
    # Receivers: eligible a hop after their voxel unit; started in submission order, each on
    # the first free node. (Slurm's backfill may start a later-eligible unit earlier; greedy
    # list scheduling in order is within a unit's time of it.)
    pending = []
    for k, s in enumerate(scenes):
        for r, seconds in enumerate(s["receivers"]):
            pending.append((voxel_end[k] + hop, k, r, seconds))
    pending.sort()
    last = max(voxel_end)
    for eligible, k, r, seconds in pending:
        begin = max(eligible, heapq.heappop(free))
        end = begin + start + seconds
        heapq.heappush(free, end)
        last = max(last, end)
    merge = sum(s["merge"] for s in scenes)
    return last + hop + start + merge


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("work")
    ap.add_argument("--nodes", default="1,2,4,8,16,64")
    ap.add_argument("--hop", default="1.0,3.0")
    ap.add_argument("--task-start", type=float, default=0.05)
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
    print("| hop | " + " | ".join(f"{n} node{'s' if n > 1 else ''}" for n in nodes) + " | critical path |")
    print("|---|" + "---:|" * (len(nodes) + 1))
    for hop in (float(h) for h in a.hop.split(",")):
        cells = []
        for n in nodes:
            wall = simulate(scenes, n, hop, a.task_start)
            cells.append(f"{wall:.1f} s ({local / wall:.2f}x)")
        critical = max(hop + a.task_start + s["voxel"] + hop + a.task_start + max(s["receivers"] or [0.0]) for s in scenes) \
            + hop + a.task_start + merge
        print(f"| {hop:g} s | " + " | ".join(cells) + f" | {critical:.1f} s |")


if __name__ == "__main__":
    main()
