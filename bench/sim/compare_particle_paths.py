#!/usr/bin/env python3
# Issue 19: old and new bench_particles / bench_collisions run alternately, R repetitions each,
# medians of particle_steps (M/s) and of the main thread's CPU ms per iteration, and their ratio.
# Usage: OLD=dir-with-old-binaries NEW=build/bench/sim bench/sim/compare_particle_paths.py [R] [label]
# (a case an old binary lacks is given None as its old filter; every case has been in the
# benchmarks at bb40d28, so OLD may be that build or any later one).
import json, os, subprocess, statistics, sys
OLD = os.environ.get("OLD", "/tmp/before-bin")
NEW = os.environ.get("NEW", "build/bench/sim")
R = int(sys.argv[1]) if len(sys.argv) > 1 else 3
# (label, binary, old filter or None, new filter)
cases = [
 ("plain no_colliders 100k 1T", "bench_particles", "no_colliders/100000/1/", "no_colliders/100000/1/"),
 ("ground airborne 100k", "bench_particles", "ground_airborne/100000/1", "ground_airborne/100000/1"),
 ("ground resting 100k", "bench_particles", "ground_resting/100000/1", "ground_resting/100000/1"),
 ("ground resting 100k 2T", "bench_particles", "ground_resting/100000/2", "ground_resting/100000/2"),
 ("ground resting 1M", "bench_particles", "ground_resting/1000000/1", "ground_resting/1000000/1"),
 ("curl noise 100k 1T", "bench_particles", "curl_noise/100000/1/", "curl_noise/100000/1/"),
 ("curl noise 100k 2T", "bench_particles", "curl_noise/100000/2/", "curl_noise/100000/2/"),
 ("pair forces 100k 1T", "bench_particles", "pair_forces/100000/1/", "pair_forces/100000/1/"),
 ("pair forces 100k 2T", "bench_particles", "pair_forces/100000/2/", "pair_forces/100000/2/"),
 ("rain on mesh 100k 1T", "bench_collisions", "rain_on_mesh/100000/1/", "rain_on_mesh/100000/1/"),
 ("rain on mesh 100k 2T", "bench_collisions", "rain_on_mesh/100000/2/", "rain_on_mesh/100000/2/"),
 ("rain settled 100k 1T", "bench_collisions", "rain_on_mesh_settled/100000/1/", "rain_on_mesh_settled/100000/1/"),
 ("rain settled 100k 2T", "bench_collisions", "rain_on_mesh_settled/100000/2/", "rain_on_mesh_settled/100000/2/"),
 ("internal_world 100k 1T", "bench_collisions", "internal_world/100000/1/", "internal_world/100000/1/"),
 ("internal_world 100k 2T", "bench_collisions", "internal_world/100000/2/", "internal_world/100000/2/"),
 ("internal_grid 100k", "bench_collisions", "internal_grid", "internal_grid"),
 ("internal_solve 100k", "bench_collisions", "internal_solve", "internal_solve"),
]
only = sys.argv[2] if len(sys.argv) > 2 else None
def run(d, b, f):
    out = subprocess.run([f"{d}/{b}", f"--benchmark_filter={f}", "--benchmark_format=json",
                          "--benchmark_min_time=0.3"], capture_output=True, text=True).stdout
    bs = json.loads(out)["benchmarks"]
    assert len(bs) == 1, (b, f, [x["name"] for x in bs])
    x = bs[0]
    return x.get("particle_steps", 0) / 1e6, x["real_time"], x["cpu_time"]
for label, b, fo, fn in cases:
    if only and only not in label: continue
    o, n = [], []
    for r in range(R):
        if fo: o.append(run(OLD, b, fo))
        n.append(run(NEW, b, fn))
    med = lambda a, k: statistics.median(v[k] for v in a) if a else float('nan')
    line = f"{label:26s} old {med(o,0):8.2f} M/s (cpu {med(o,2):7.1f} ms)  new {med(n,0):8.2f} M/s (cpu {med(n,2):7.1f} ms)"
    if fo: line += f"  ratio {med(n,0)/med(o,0):5.2f}x (cpu ratio {med(o,2)/med(n,2):5.2f}x)"
    print(line, flush=True)
