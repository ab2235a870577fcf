#!/usr/bin/env python3
"""Two-particle head-on collision tests for pair_style granular damping routes.
Generates a deck, runs LAMMPS (single process), parses per-step thermo output,
reconstructs the half-step velocities that LAMMPS used in the force call,
subtracts the exact elastic force and compares the viscous force with AR07 eq.(5),
and measures the coefficient of restitution."""
import math, subprocess, sys, os, re, json

LMP25 = os.path.join(os.environ.get("GRAINBENCH_LAMMPS_2025") or os.path.expanduser("~/.local/share/grainbench/lammps-2025"), "bin", "lmp")
LMP21 = "lmp"
D = os.environ.get("OUT", "runs/lammps-damping-routes")
os.makedirs(f"{D}/decks", exist_ok=True)
os.makedirs(f"{D}/out", exist_ok=True)

def deck(name, pair_coeff, R1, R2, m1, m2, vrel, dt, nsteps, dim=3, extra_pair=""):
    gap = 1e-3*(R1+R2)*0  # start just touching-1e-6
    x1 = 0.0
    x2 = R1 + R2 + 1e-6
    M = m1 + m2
    v1 = vrel*m2/M
    v2 = -vrel*m1/M
    zlo, zhi = (-10, 10) if dim == 3 else (-0.5, 0.5)
    s = f"""# {name}
units lj
atom_style sphere
dimension {dim}
boundary p p p
atom_modify map array
comm_modify vel yes
newton off
region box block -10 10 -10 10 {zlo} {zhi}
create_box 1 box
create_atoms 1 single {x1!r} 0 0
create_atoms 1 single {x2!r} 0 0
set atom 1 diameter {2*R1!r}
set atom 2 diameter {2*R2!r}
set atom 1 mass {m1!r}
set atom 2 mass {m2!r}
set atom 1 vx {v1!r}
set atom 2 vx {v2!r}
pair_style granular
pair_coeff * * {pair_coeff}
neighbor 0.5 bin
fix 1 all nve/sphere
{"fix 2 all enforce2d" if dim == 2 else ""}
timestep {dt!r}
variable x1 equal x[1]
variable x2 equal x[2]
variable v1 equal vx[1]
variable v2 equal vx[2]
variable f1 equal fx[1]
variable f2 equal fx[2]
thermo_style custom step v_x1 v_x2 v_v1 v_v2 v_f1 v_f2
thermo_modify format float %.17g norm no
thermo 1
run {nsteps}
"""
    path = f"{D}/decks/in.{name}"
    open(path, "w").write(s)
    return path

def run(path, name, exe=LMP25):
    log = f"{D}/out/log.{name}"
    p = subprocess.run([exe, "-in", path, "-log", log, "-screen", "none"],
                       capture_output=True, text=True)
    txt = open(log).read() if os.path.exists(log) else ""
    err = [l for l in txt.splitlines() if l.startswith("ERROR")]
    rows = []
    if not err:
        on = False
        for l in txt.splitlines():
            if l.strip().startswith("Step"):
                on = True; continue
            if on:
                if l.startswith("Loop time"):
                    break
                try:
                    rows.append([float(t) for t in l.split()])
                except ValueError:
                    pass
    return rows, err, p.returncode

def analyse(rows, R1, R2, m1, m2, dt, Ne, Kn, zeta, alpha_fn=None):
    """Return list of (h, hdot, Fv_measured, Fv_AR07, ratio) and restitution."""
    mstar = m1*m2/(m1+m2); Rs = R1*R2/(R1+R2)
    out = []
    for st, x1, x2, v1, v2, f1, f2 in rows:
        if st == 0: continue
        h = R1 + R2 - (x2 - x1)
        if h <= 0 or f1 == 0.0: continue
        v1h = v1 - 0.5*dt*f1/m1
        v2h = v2 - 0.5*dt*f2/m2
        hd = v1h - v2h
        Fn = -f1            # repulsive normal force magnitude on atom 1 (pushes -x)
        Fv = Fn - Ne(h)
        a = zeta*math.sqrt(2*mstar*Kn(h)) if alpha_fn is None else alpha_fn(h)
        Fa = a*hd
        out.append((h, hd, Fv, Fa, Fv/Fa if Fa != 0 else float('nan')))
    vin = rows[0][3]-rows[0][4]
    vout = rows[-1][3]-rows[-1][4]
    st, x1, x2 = rows[-1][:3]
    sep = (x2 - x1) > R1 + R2
    e = -vout/vin if sep else None
    return out, e

def restitution_exact(Ne, alpha, mstar, v0, nsteps=400000, tmax=None):
    """RK4 integrate m* h'' = -Ne(h) - alpha(h) h' from h=0,h'=v0 until h<0 again."""
    # estimate contact time scale
    def acc(h, v):
        hh = max(h, 0.0)
        return (-Ne(hh) - alpha(hh)*v)/mstar
    # adaptive: first rough run to get duration
    def integ(dt, tmax):
        h, v, t = 0.0, v0, 0.0
        while True:
            k1h, k1v = v, acc(h, v)
            k2h, k2v = v+0.5*dt*k1v, acc(h+0.5*dt*k1h, v+0.5*dt*k1v)
            k3h, k3v = v+0.5*dt*k2v, acc(h+0.5*dt*k2h, v+0.5*dt*k2v)
            k4h, k4v = v+dt*k3v, acc(h+dt*k3h, v+dt*k3v)
            hn = h + dt/6*(k1h+2*k2h+2*k3h+k4h)
            vn = v + dt/6*(k1v+2*k2v+2*k3v+k4v)
            t += dt
            if hn < 0:
                # linear interpolation of v at crossing (small error ~dt^2)
                fr = h/(h-hn)
                return -(v + fr*(vn-v))/v0, t
            h, v = hn, vn
            if t > tmax: return None, t
    return integ
