#!/usr/bin/env python3
"""Times a reference implementation of `spring_step` on networks exported
by `chisel bench relax --export DIR`: one fused CSR-gather kernel per
iteration in Taichi (a JIT-compiled GPU/CPU framework), the kind of tool
the issue's CPU targets are measured against. It computes the same step as
`kernels/spring_step.wgsl` (eq. 4.4-4.7 on displacements from rest, the
biphasic law, the rest length from the rest difference), double-buffered,
on the CPU with every core (or `--threads`).

    pip install taichi numpy
    chisel bench relax ../shared/data/fran_cut.vtk --grid 45,49 --refine 1,8,13 \\
        --backend cpu --solver explicit --export /tmp/nets
    python3 scripts/reference_spring_step.py /tmp/nets/x1 /tmp/nets/x8 /tmp/nets/x13

Prints iterations per second for each folder (best of three timed runs of
`--seconds` each, after a warm-up), and checks the result against the
folder's own explicit step written in numpy (float64) on a few nodes.
"""

import argparse
import json
import os
import time

import numpy as np


def load(folder):
    with open(os.path.join(folder, "network.json")) as f:
        meta = json.load(f)

    def arr(name, dtype, cols=None):
        a = np.fromfile(os.path.join(folder, name), dtype=np.dtype(dtype).newbyteorder("<"))
        return a.reshape(-1, cols) if cols else a

    net = {
        "meta": meta,
        "rest": arr("rest.f32", np.float32, 4),
        "u0": arr("displacement.f32", np.float32, 4),
        "offsets": arr("offsets.u32", np.uint32),
        "entries": arr("entries.u32", np.uint32),
        "materials": arr("materials.f32", np.float32, 4),
    }
    n, free = meta["nodes"], meta["free"]
    assert net["rest"].shape == (n, 4) and net["u0"].shape == (n, 4)
    assert net["offsets"].shape == (free + 1,) and net["entries"].shape == (meta["entries"],)
    assert net["materials"].shape == (16, 4)
    return net


def numpy_step(net, u, vel, nodes):
    """The explicit step of `nodes` in float64 (a check, not a timing)."""
    rest, off, ent, mats = net["rest"], net["offsets"], net["entries"], net["materials"]
    dt, gamma = net["meta"]["dt"], net["meta"]["damping"]
    out_u, out_v = {}, {}
    for i in nodes:
        g = np.zeros(3)
        for e in ent[off[i]:off[i + 1]]:
            j, m = int(e & 0x0FFFFFFF), int(e >> 28)
            d0 = rest[i, :3].astype(np.float64) - rest[j, :3]
            r = d0 + (u[i, :3].astype(np.float64) - u[j, :3])
            ln, l0 = np.linalg.norm(r), np.linalg.norm(d0)
            if ln > 0:
                ext = ln - l0
                c1, dc, knee = mats[m, 0], mats[m, 1], mats[m, 2]
                g += (c1 * ext + dc * max(ext - knee * l0, 0.0)) / ln * r
        a = (-gamma * vel[i, :3] - g) * u[i, 3]
        out_v[i] = vel[i, :3] + dt * a
        out_u[i] = u[i, :3] + dt * out_v[i]
    return out_u, out_v


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("folders", nargs="+")
    p.add_argument("--seconds", type=float, default=3.0)
    p.add_argument("--threads", type=int, default=os.cpu_count())
    args = p.parse_args()

    import taichi as ti

    ti.init(arch=ti.cpu, cpu_max_num_threads=args.threads, default_fp=ti.f32, log_level=ti.WARN)
    for folder in args.folders:
        net = load(folder)
        meta = net["meta"]
        n, free = meta["nodes"], meta["free"]
        rest = ti.Vector.field(3, ti.f32, n)
        pos = [ti.Vector.field(4, ti.f32, n) for _ in range(2)]
        vel = ti.Vector.field(3, ti.f32, free)
        off = ti.field(ti.i32, free + 1)
        ent = ti.field(ti.i32, meta["entries"])
        mat = ti.Vector.field(4, ti.f32, 16)
        rest.from_numpy(np.ascontiguousarray(net["rest"][:, :3]))
        off.from_numpy(net["offsets"].astype(np.int32))
        ent.from_numpy(net["entries"].view(np.int32))
        mat.from_numpy(net["materials"])
        for q in pos:
            q.from_numpy(net["u0"])

        @ti.kernel
        def step(pin: ti.template(), pout: ti.template(), dt: ti.f32, gamma: ti.f32):
            for i in range(free):
                x0 = rest[i]
                p_i = pin[i]
                u = ti.Vector([p_i[0], p_i[1], p_i[2]])
                g = ti.Vector([0.0, 0.0, 0.0])
                for k in range(off[i], off[i + 1]):
                    e = ent[k]
                    j = e & 0x0FFFFFFF
                    c = mat[(e >> 28) & 15]
                    p_j = pin[j]
                    d0 = x0 - rest[j]
                    l0 = d0.norm()
                    r = d0 + (u - ti.Vector([p_j[0], p_j[1], p_j[2]]))
                    ln = r.norm()
                    if ln > 0.0:
                        ext = ln - l0
                        g += (c[0] * ext + c[1] * ti.max(ext - c[2] * l0, 0.0)) / ln * r
                a = (-gamma * vel[i] - g) * p_i[3]
                v2 = vel[i] + dt * a
                vel[i] = v2
                u2 = u + dt * v2
                pout[i] = ti.Vector([u2[0], u2[1], u2[2], p_i[3]])

        dt, gamma = meta["dt"], meta["damping"]
        # Check one step against float64 numpy on a spread of nodes.
        vel.fill(0.0)
        step(pos[0], pos[1], dt, gamma)
        ti.sync()
        nodes = np.linspace(0, free - 1, 64).astype(int)
        want_u, _ = numpy_step(net, net["u0"], np.zeros((free, 3)), nodes)
        got = pos[1].to_numpy()
        scale = max(np.abs(net["u0"][:, :3]).max(), 1e-30)
        err = max(np.abs(got[i, :3] - want_u[i]).max() for i in nodes) / scale
        assert err < 1e-3, f"{folder}: the step differs from numpy by {err:.2e} of the bone move"

        for _ in range(8):
            step(pos[0], pos[1], dt, gamma)
            step(pos[1], pos[0], dt, gamma)
        ti.sync()
        rates = []
        for _ in range(3):
            it, t0 = 0, time.perf_counter()
            while time.perf_counter() - t0 < args.seconds:
                for _ in range(8):
                    step(pos[0], pos[1], dt, gamma)
                    step(pos[1], pos[0], dt, gamma)
                ti.sync()
                it += 16
            rates.append(it / (time.perf_counter() - t0))
        print(
            json.dumps(
                {
                    "network": folder,
                    "nodes": n,
                    "entries": meta["entries"],
                    "tool": f"taichi {'.'.join(map(str, ti.__version__))} (cpu, {args.threads} threads)",
                    "iterations_per_second": round(max(rates), 1),
                    "runs": [round(r, 1) for r in rates],
                    "check_error_vs_float64": float(f"{err:.2e}"),
                }
            ),
            flush=True,
        )


if __name__ == "__main__":
    main()
