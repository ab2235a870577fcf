#!/usr/bin/env python3
"""pydem: a small reference DEM code joining grainbench through its exchange format.

An independent example of a code joining grainbench through the neutral exchange format
(docs/exchange-format.md), written from the format and the papers without reading
grainbench's engine. Pure Python 3, standard library only.

    python3 pydem.py EXCHANGE_DIR OUTPUT_DIR
    python3 pydem.py --version

It reads EXCHANGE_DIR/exchange.json and the grains file it names, runs the DEM stages, and
writes OUTPUT_DIR/particles.csv, contacts.csv, the optional trace files and, last,
status.txt (each atomically: a temporary file in the same directory, then os.replace).

Scope:
  * 3D spheres in a periodic orthorhombic cell [0, L) fixed in time; pairs by the nearest
    image, positions wrapped back into the cell;
  * the Hertz-Mindlin law of AR07 (Agnolin & Roux, PRE 76, 061302, 2007) in reduced units
    (force unit P_ref a^2 with P_ref = 1): Hertz normal force (1), Mindlin tangential
    stiffness (3) with the incremental tangential force, its transport with the contact and
    the Walton rescaling on unloading (App. A-B), normal viscous damping (5), Coulomb's
    condition on the elastic normal force; mu = "inf": no sliding;
  * `fixed-volume` stages run in order (mu and kappa of each stage; a mu change starts
    without contact history and with spins at zero, a kappa change keeps both), each to its own `max_time` or, unless
    `full_time`, to the equilibrium criteria (force, moment, kinetic energy per grain,
    checked every `check_every` steps, held for `criteria.window`);
  * velocity Verlet with the stage's time step `dt`;
  * the optional trace of few-body runs (`trace` in exchange.json).

Limits (refused with exit status 2): other exchange versions, 2D, the linear law, cohesion
(`sjkr`, `dmt`), stress-controlled (`compress`) or `aggregate` stages, strain rates, the
final relaxation (`relax`), and more than 500 grains (the pair search is O(N^2) per step).
Also refused: a cell side shorter than twice the largest diameter (the nearest image must be
the only image in reach). A non-finite position or velocity ends the run with status `failed`
and exit status 1.

Conventions: forces act on j as +N n + T, n the unit vector from i to j (nearest image);
contacts.csv and the trace report N, N_e and T of the force evaluation at the reported
positions (made with the half-step velocities of velocity Verlet). Velocity Verlet runs on
across stage boundaries: a stage's first half kick uses the forces of the previous stage's last
step, its law acts from its first force evaluation on, except at a mu change, which starts afresh
(no contact history, spins at zero, forces evaluated again) as the format says.
"""

import argparse
import csv
import json
import math
import os
import sys
import time

VERSION = "pydem 1.0"
MAX_GRAINS = 500  # all-pairs search: N(N-1)/2 pair tests per step


class InputError(Exception):
    """An input the code refuses: `pydem: error: <file>: <field>: <what>`, exit status 2."""

    def __init__(self, file, field, what):
        super().__init__(f"{file}: {field}: {what}" if field else f"{file}: {what}")


# ---------------------------------------------------------------------------------------------
# Reading the exchange


def number(obj, key, where, file="exchange.json", low=None, positive=False):
    """obj[key] as a finite float (`where`: the field's path, for messages)."""
    if key not in obj:
        raise InputError(file, where, "missing")
    v = obj[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise InputError(file, where, f"expected a finite number, got {json.dumps(v)}")
    if positive and v <= 0 or low is not None and v < low:
        raise InputError(file, where, f"out of range: {v!r}")
    return float(v)


def got(obj, key):
    """obj[key] as JSON, for messages."""
    return json.dumps(obj.get(key))


def friction(v, where):
    """mu: a number >= 0, or "inf" (contacts never slide) -> math.inf."""
    if v == "inf":
        return math.inf
    return number({"mu": v}, "mu", where, low=0.0)


def read_exchange(exdir):
    name = "exchange.json"
    try:
        with open(os.path.join(exdir, name), encoding="utf-8") as f:
            ex = json.load(f)
    except OSError as e:
        raise InputError(os.path.join(exdir, name), "", e.strerror or str(e))
    except ValueError as e:
        raise InputError(name, "", f"not JSON: {e}")
    if not isinstance(ex, dict):
        raise InputError(name, "", "expected a JSON object")
    if ex.get("format") != "grainbench-exchange":
        raise InputError(name, "format", f'expected "grainbench-exchange", got {got(ex, "format")}')
    if ex.get("version") != 1:
        raise InputError(name, "version", f"pydem reads version 1 only, got {got(ex, 'version')}")
    if ex.get("dimension") != 3:
        raise InputError(name, "dimension", f"pydem runs 3D spheres only, got {got(ex, 'dimension')}")
    cell = ex.get("cell") or {}
    if cell.get("periodic") is not True:
        raise InputError(name, "cell.periodic", "pydem runs periodic cells only")
    lengths = cell.get("lengths")
    if not isinstance(lengths, list) or len(lengths) != 3:
        raise InputError(name, "cell.lengths", "expected 3 side lengths")
    lengths = [number({"L": x}, "L", f"cell.lengths[{k}]", positive=True) for k, x in enumerate(lengths)]

    law = ex.get("law") or {}
    if law.get("kind") != "hertz-mindlin":
        raise InputError(name, "law.kind", f"pydem runs the hertz-mindlin law only, got {got(law, 'kind')}")
    for key in ("sjkr", "dmt"):
        if law.get(key) is not None:
            raise InputError(name, f"law.{key}", "cohesion is not supported by pydem")
    law = {
        "kappa": number(law, "kappa", "law.kappa", positive=True),
        "mu": friction(law.get("mu"), "law.mu"),
        "zeta": number(law, "zeta", "law.zeta", low=0.0),
        "poisson": number(law, "poisson", "law.poisson", low=-1.0),
    }
    if law["poisson"] >= 1.0:  # K_T/K_N = (2 - 2nu)/(2 - nu) > 0 needs nu < 1
        raise InputError(name, "law.poisson", f"out of range: {law['poisson']!r}")

    stages = ex.get("stages")
    if not isinstance(stages, list) or not stages:
        raise InputError(name, "stages", "expected a non-empty list")
    out_stages = []
    for k, s in enumerate(stages):
        w = f"stages[{k}]"
        if not isinstance(s, dict):
            raise InputError(name, w, "expected an object")
        if s.get("kind") != "fixed-volume":
            raise InputError(name, f"{w}.kind",
                             f"{got(s, 'kind')} is not supported (pydem runs fixed-volume stages only)")
        if s.get("max_strain_rate", 0.0) != 0.0:
            raise InputError(name, f"{w}.max_strain_rate", "pydem keeps the cell fixed (0 only)")
        if s.get("relax") is not None:
            raise InputError(name, f"{w}.relax", "the final relaxation is not supported by pydem")
        tol = s.get("tolerances") or {}
        crit = s.get("criteria") or {}
        out_stages.append({
            "dt": number(s, "dt", f"{w}.dt", positive=True),
            "max_time": number(s, "max_time", f"{w}.max_time", low=0.0),
            "mu": friction(s["mu"], f"{w}.mu") if "mu" in s else law["mu"],
            "kappa": number(s, "kappa", f"{w}.kappa", positive=True) if "kappa" in s else law["kappa"],
            "full_time": bool(s.get("full_time", False)),
            "check_every": max(1, int(number(s, "check_every", f"{w}.check_every", positive=True))),
            "force": number(tol, "force", f"{w}.tolerances.force", low=0.0),
            "moment": number(tol, "moment", f"{w}.tolerances.moment", low=0.0),
            "kinetic": number(tol, "kinetic_per_grain", f"{w}.tolerances.kinetic_per_grain", low=0.0),
            "window": (number(crit, "window", f"{w}.criteria.window", low=0.0)
                       if crit.get("window") is not None else 0.0),
        })

    trace = ex.get("trace")
    if trace is not None:
        if not isinstance(trace, dict):
            raise InputError(name, "trace", "expected an object")
        for key in ("grains", "contacts"):
            if not isinstance(trace.get(key), str) or not trace[key] or os.sep in trace[key]:
                raise InputError(name, f"trace.{key}", "expected a file name")
        trace = {"every": number(trace, "every", "trace.every", low=0.0),
                 "grains": trace["grains"], "contacts": trace["contacts"]}

    output = {"particles": "particles.csv", "contacts": "contacts.csv", "status": "status.txt"}
    output.update({k: v for k, v in (ex.get("output") or {}).items() if k in output and isinstance(v, str)})
    pfile = (ex.get("particles") or {}).get("file", "particles.csv")
    return {"lengths": lengths, "law": law, "stages": out_stages, "trace": trace,
            "output": output, "particles": os.path.join(exdir, pfile), "pfile": pfile,
            "count": (ex.get("particles") or {}).get("count")}


def read_particles(path, name, count):
    """Grains sorted by id: lists id, x, y, z, r, m, I, vx, vy, vz, wx, wy, wz."""
    try:
        with open(path, newline="", encoding="utf-8") as f:
            rows = list(csv.reader(f))
    except OSError as e:
        raise InputError(path, "", e.strerror or str(e))
    if not rows:
        raise InputError(name, "", "empty file")
    header = [h.strip() for h in rows[0]]
    col = {h: k for k, h in enumerate(header)}
    for h in ("id", "x", "y", "z", "diameter"):
        if h not in col:
            raise InputError(name, "header", f"no column `{h}`")
    grains = []
    for line, row in enumerate(rows[1:], start=2):
        if not row or row[0].lstrip().startswith("#"):
            continue

        def val(h, default=None):
            if h not in col:
                return default
            try:
                v = float(row[col[h]])
            except (IndexError, ValueError):
                v = math.nan
            if not math.isfinite(v):
                raise InputError(name, f"line {line}, column `{h}`", "expected a finite number")
            return v

        gid, d = val("id"), val("diameter")
        if gid < 0 or gid != int(gid):
            raise InputError(name, f"line {line}, column `id`", "expected a whole number >= 0")
        if d <= 0:
            raise InputError(name, f"line {line}, column `diameter`", "expected a positive diameter")
        m = val("mass", d ** 3)  # default: m = d^3 (mass unit: a grain of diameter a)
        inertia = val("inertia", m * d * d / 10.0)  # solid sphere: I = m d^2 / 10
        if m <= 0 or inertia <= 0:
            raise InputError(name, f"line {line}, column `mass`/`inertia`", "expected positive values")
        grains.append((int(gid), val("x"), val("y"), val("z"), d / 2.0, m, inertia,
                       val("vx", 0.0), val("vy", 0.0), val("vz", 0.0),
                       val("wx", 0.0), val("wy", 0.0), val("wz", 0.0)))
    if len(grains) > MAX_GRAINS:
        raise InputError(name, "rows", f"{len(grains)} grains: pydem handles at most {MAX_GRAINS} "
                                       "(its pair search tests all N(N-1)/2 pairs every step)")
    if count is not None and count != len(grains):
        raise InputError(name, "rows", f"{len(grains)} grains, exchange.json says particles.count = {count}")
    grains.sort()
    ids = [g[0] for g in grains]
    if len(set(ids)) != len(ids):
        raise InputError(name, "id", "an id is listed twice")
    cols = list(zip(*grains)) if grains else [()] * 13
    return [list(c) for c in cols]


# ---------------------------------------------------------------------------------------------
# Forces


def compute_forces(g, law, hist, dt):
    """Contact forces and torques at the current positions; returns the new history.

    `g`: the grains (lists); `law`: Et, mu, zeta, kt_over_kn; `hist`: {(i, j): (Tx, Ty, Tz,
    K_T)} of the contacts of the previous evaluation; `dt`: the time since then (0 for the
    evaluation at t = 0: no rotation, no increment).
    Fills g["fx"] ... g["tz"] and g["contacts"]: (i, j, h, N, N_e, Tx, Ty, Tz) per pair with
    h > 0, i < j (indices, sorted by id).
    """
    x, y, z, r, m = g["x"], g["y"], g["z"], g["r"], g["m"]
    vx, vy, vz, wx, wy, wz = g["vx"], g["vy"], g["vz"], g["wx"], g["wy"], g["wz"]
    Lx, Ly, Lz = g["L"]
    hx, hy, hz = 0.5 * Lx, 0.5 * Ly, 0.5 * Lz
    n = len(x)
    fx, fy, fz = [0.0] * n, [0.0] * n, [0.0] * n
    tx, ty, tz = [0.0] * n, [0.0] * n, [0.0] * n
    Et, mu, zeta, ktr = law["Et"], law["mu"], law["zeta"], law["kt_over_kn"]
    tangential = mu > 0.0
    sqrt = math.sqrt
    new_hist = {}
    contacts = []
    for i in range(n - 1):
        xi, yi, zi, ri, mi = x[i], y[i], z[i], r[i], m[i]
        for j in range(i + 1, n):
            rs = ri + r[j]
            # branch vector i -> j, nearest image
            dx = x[j] - xi
            if dx > hx:
                dx -= Lx
            elif dx < -hx:
                dx += Lx
            if dx >= rs or dx <= -rs:
                continue
            dy = y[j] - yi
            if dy > hy:
                dy -= Ly
            elif dy < -hy:
                dy += Ly
            if dy >= rs or dy <= -rs:
                continue
            dz = z[j] - zi
            if dz > hz:
                dz -= Lz
            elif dz < -hz:
                dz += Lz
            d2 = dx * dx + dy * dy + dz * dz
            if d2 >= rs * rs:
                continue
            d = sqrt(d2)
            h = rs - d  # overlap > 0
            nx, ny, nz = dx / d, dy / d, dz / d
            rj = r[j]
            Rs = ri * rj / rs  # R* = r_i r_j / (r_i + r_j)
            ms = mi * m[j] / (mi + m[j])  # m* = m_i m_j / (m_i + m_j)
            # AR07 (1): N_e = (2/3) Et sqrt(R*) h^(3/2) (= Et sqrt(a) h^(3/2) / 3 for equal
            # spheres of diameter a), with the normal stiffness K_N = dN_e/dh = Et sqrt(R* h)
            KN = Et * sqrt(Rs * h)
            Ne = (2.0 / 3.0) * KN * h
            # relative velocity of j w.r.t. i at the contact point:
            # v = v_j - v_i - (r_i w_i + r_j w_j) x n
            ax = ri * wx[i] + rj * wx[j]
            ay = ri * wy[i] + rj * wy[j]
            az = ri * wz[i] + rj * wz[j]
            ux = vx[j] - vx[i] - (ay * nz - az * ny)
            uy = vy[j] - vy[i] - (az * nx - ax * nz)
            uz = vz[j] - vz[i] - (ax * ny - ay * nx)
            un = ux * nx + uy * ny + uz * nz
            # AR07 (5): viscous normal force, alpha = 2 zeta sqrt(m* K_N) (zeta: fraction of critical)
            N = Ne - 2.0 * zeta * sqrt(ms * KN) * un  # not clipped
            Tx = Ty = Tz = 0.0
            if tangential:
                KT = ktr * KN  # AR07 (3): K_T = (2 - 2nu)/(2 - nu) K_N
                old = hist.get((i, j))
                if old is not None:
                    Tx, Ty, Tz, KT0 = old
                    # (a) transport: project onto the new tangent plane, keep |T| (AR07 App. B)
                    t2 = Tx * Tx + Ty * Ty + Tz * Tz
                    if t2 > 0.0:
                        tn = Tx * nx + Ty * ny + Tz * nz
                        Tx -= tn * nx
                        Ty -= tn * ny
                        Tz -= tn * nz
                        p2 = Tx * Tx + Ty * Ty + Tz * Tz
                        s = sqrt(t2 / p2) if p2 > 0.0 else 0.0
                        Tx *= s
                        Ty *= s
                        Tz *= s
                        # (b) rotate about n by the mean spin of the pair (AR07 App. B), Rodrigues
                        a = 0.5 * ((wx[i] + wx[j]) * nx + (wy[i] + wy[j]) * ny + (wz[i] + wz[j]) * nz) * dt
                        if a != 0.0:
                            c, sn = math.cos(a), math.sin(a)
                            Tx, Ty, Tz = (Tx * c + (ny * Tz - nz * Ty) * sn,
                                          Ty * c + (nz * Tx - nx * Tz) * sn,
                                          Tz * c + (nx * Ty - ny * Tx) * sn)
                        # (c) Walton: scale T down with K_T when the contact unloads (AR07 App. A)
                        if KT < KT0:
                            s = KT / KT0
                            Tx *= s
                            Ty *= s
                            Tz *= s
                # (d) AR07 (3): dT = -K_T v_t dt, v_t the tangential relative velocity
                c = KT * dt
                Tx -= c * (ux - un * nx)
                Ty -= c * (uy - un * ny)
                Tz -= c * (uz - un * nz)
                # (e) Coulomb on the elastic normal force: |T| <= mu N_e
                if mu != math.inf:
                    cap = mu * Ne if Ne > 0.0 else 0.0
                    t2 = Tx * Tx + Ty * Ty + Tz * Tz
                    if t2 > cap * cap:
                        s = cap / sqrt(t2)
                        Tx *= s
                        Ty *= s
                        Tz *= s
                new_hist[(i, j)] = (Tx, Ty, Tz, KT)
            # force on j: N n + T; on i: the opposite
            Fx, Fy, Fz = N * nx + Tx, N * ny + Ty, N * nz + Tz
            fx[j] += Fx
            fy[j] += Fy
            fz[j] += Fz
            fx[i] -= Fx
            fy[i] -= Fy
            fz[i] -= Fz
            # torques: on j (-r_j n) x T, on i (r_i n) x (-T): both -r n x T
            cx, cy, cz = ny * Tz - nz * Ty, nz * Tx - nx * Tz, nx * Ty - ny * Tx
            tx[j] -= rj * cx
            ty[j] -= rj * cy
            tz[j] -= rj * cz
            tx[i] -= ri * cx
            ty[i] -= ri * cy
            tz[i] -= ri * cz
            contacts.append((i, j, h, N, Ne, Tx, Ty, Tz))
    g["fx"], g["fy"], g["fz"], g["tx"], g["ty"], g["tz"] = fx, fy, fz, tx, ty, tz
    g["contacts"] = contacts
    return new_hist


def criteria(g):
    """Largest net force and moment on a grain, kinetic energy per grain (rotation counted
    only for grains with a contact, as grainbench's criteria do)."""
    n = len(g["x"])
    if n == 0:
        return 0.0, 0.0, 0.0
    touching = set()
    for c in g["contacts"]:
        touching.add(c[0])
        touching.add(c[1])
    fmax = max(math.sqrt(a * a + b * b + c * c) for a, b, c in zip(g["fx"], g["fy"], g["fz"]))
    tmax = max(math.sqrt(a * a + b * b + c * c) for a, b, c in zip(g["tx"], g["ty"], g["tz"]))
    ek = 0.0
    for i in range(n):
        ek += 0.5 * g["m"][i] * (g["vx"][i] ** 2 + g["vy"][i] ** 2 + g["vz"][i] ** 2)
        if i in touching:
            ek += 0.5 * g["I"][i] * (g["wx"][i] ** 2 + g["wy"][i] ** 2 + g["wz"][i] ** 2)
    return fmax, tmax, ek / n


# ---------------------------------------------------------------------------------------------
# Output


def write_atomic(path, text):
    tmp = f"{path}.tmp{os.getpid()}"
    with open(tmp, "w", encoding="utf-8", newline="") as f:
        f.write(text)
    os.replace(tmp, path)


def contact_rows(g):
    ids = g["id"]
    return [f"{ids[i]},{ids[j]},{N!r},{Ne!r},{Tx!r},{Ty!r},{Tz!r}\n"
            for i, j, h, N, Ne, Tx, Ty, Tz in g["contacts"]]


class Trace:
    """Frames at t = 0, then whenever `every` has passed since the last one, and at the end."""

    def __init__(self, spec):
        self.spec, self.grains, self.contacts, self.last = spec, [], [], None

    def frame(self, g, t, dt):
        if self.last is not None and t - self.last < self.spec["every"] - 1e-6 * dt:
            return
        self.last = t
        ts, ids = repr(t), g["id"]
        self.grains.extend(
            "%s,%d,%r,%r,%r,%r,%r,%r,%r,%r,%r\n" % (ts, ids[i], g["x"][i], g["y"][i], g["z"][i],
                                                   g["vx"][i], g["vy"][i], g["vz"][i],
                                                   g["wx"][i], g["wy"][i], g["wz"][i])
            for i in range(len(ids)))
        self.contacts.extend(f"{ts},{ids[i]},{ids[j]},{-h!r},{N!r},{Ne!r},{Tx!r},{Ty!r},{Tz!r}\n"
                             for i, j, h, N, Ne, Tx, Ty, Tz in g["contacts"])

    def write(self, outdir, g, t):
        if self.last != t:
            self.last = None
            self.frame(g, t, 0.0)
        write_atomic(os.path.join(outdir, self.spec["grains"]),
                     "t,id,x,y,z,vx,vy,vz,wx,wy,wz\n" + "".join(self.grains))
        write_atomic(os.path.join(outdir, self.spec["contacts"]),
                     "t,i,j,gap,fn,fn_elastic,ft_x,ft_y,ft_z\n" + "".join(self.contacts))


# ---------------------------------------------------------------------------------------------
# Time stepping


def run(ex, g, outdir):
    """Runs the stages; returns (status, steps, time, loop seconds)."""
    n = len(g["x"])
    Lx, Ly, Lz = g["L"]
    x, y, z, m, inertia = g["x"], g["y"], g["z"], g["m"], g["I"]
    vx, vy, vz, wx, wy, wz = g["vx"], g["vy"], g["vz"], g["wx"], g["wy"], g["wz"]
    trace = Trace(ex["trace"]) if ex["trace"] else None
    ktr = (2.0 - 2.0 * ex["law"]["poisson"]) / (2.0 - ex["law"]["poisson"])
    hist, prev_mu = {}, None
    t, steps, status, loop = 0.0, 0, "time-limit", 0.0
    for stage in ex["stages"]:
        # Each stage has its own clock: it ends when its own elapsed time reaches its
        # max_time (the format's max_steps = ceil(max_time / dt) is counted per stage, and the
        # decks of the other codes run max_steps per stage); t (reported) is the total time.
        law = {"Et": stage["kappa"] ** 1.5,  # AR07 (21): kappa = (Et/P)^(2/3), P = 1
               "mu": stage["mu"], "zeta": ex["law"]["zeta"], "kt_over_kn": ktr}
        if prev_mu is not None and stage["mu"] != prev_mu:
            # A mu change starts afresh (docs/exchange-format.md): no contact history, spins
            # at zero, forces evaluated again; a kappa change keeps the history.
            for i in range(n):
                wx[i] = wy[i] = wz[i] = 0.0
            hist = compute_forces(g, law, {}, 0.0)
        prev_mu = stage["mu"]
        dt = stage["dt"]
        hk = [0.5 * dt / mi for mi in m]  # half kicks
        hr = [0.5 * dt / ii for ii in inertia]
        if "fx" not in g:
            # forces at t = 0 (no tangential increment); afterwards the Verlet loop carries
            # the forces of the last step into the next stage, whose law (and dt) acts from
            # its first step on
            hist = compute_forces(g, law, hist, 0.0)
            if trace:
                trace.frame(g, t, dt)
        t0, k, held = t, 0, None
        nsteps = max(0, math.ceil(stage["max_time"] / dt - 1e-9))
        status = "time-limit"
        start = time.perf_counter()
        while k < nsteps:
            fx, fy, fz, tx, ty, tz = g["fx"], g["fy"], g["fz"], g["tx"], g["ty"], g["tz"]
            # velocity Verlet: half kick, drift (wrapped into [0, L))
            for i in range(n):
                a, b = hk[i], hr[i]
                vx[i] += a * fx[i]
                vy[i] += a * fy[i]
                vz[i] += a * fz[i]
                wx[i] += b * tx[i]
                wy[i] += b * ty[i]
                wz[i] += b * tz[i]
                xi, yi, zi = x[i] + dt * vx[i], y[i] + dt * vy[i], z[i] + dt * vz[i]
                if not 0.0 <= xi < Lx:
                    xi %= Lx
                    xi = 0.0 if xi >= Lx else xi
                if not 0.0 <= yi < Ly:
                    yi %= Ly
                    yi = 0.0 if yi >= Ly else yi
                if not 0.0 <= zi < Lz:
                    zi %= Lz
                    zi = 0.0 if zi >= Lz else zi
                x[i], y[i], z[i] = xi, yi, zi
            # forces at the new positions (half-step velocities: AR07 (3) increment over dt)
            hist = compute_forces(g, law, hist, dt)
            fx, fy, fz, tx, ty, tz = g["fx"], g["fy"], g["fz"], g["tx"], g["ty"], g["tz"]
            acc = 0.0  # any NaN/inf in the state makes the sum non-finite
            for i in range(n):
                a, b = hk[i], hr[i]
                vx[i] += a * fx[i]
                vy[i] += a * fy[i]
                vz[i] += a * fz[i]
                wx[i] += b * tx[i]
                wy[i] += b * ty[i]
                wz[i] += b * tz[i]
                acc += x[i] + y[i] + z[i] + vx[i] + vy[i] + vz[i] + wx[i] + wy[i] + wz[i]
            k += 1
            steps += 1
            t = t0 + k * dt
            if not math.isfinite(acc):
                loop += time.perf_counter() - start
                return "failed", steps, t, loop
            if trace:
                trace.frame(g, t, dt)
            if not stage["full_time"] and k % stage["check_every"] == 0:
                fmax, tmax, ek = criteria(g)
                if fmax <= stage["force"] and tmax <= stage["moment"] and ek <= stage["kinetic"]:
                    held = t if held is None else held
                    if t - held >= stage["window"] - 1e-6 * dt:
                        status = "equilibrium"
                        break
                else:
                    held = None
        loop += time.perf_counter() - start
    if trace:
        trace.write(outdir, g, t)
    return status, steps, t, loop


def main(argv=None):
    p = argparse.ArgumentParser(prog="pydem", description=__doc__.split("\n")[0])
    p.add_argument("--version", action="version",
                   version=f"{VERSION} (grainbench exchange-format example, Python {sys.version.split()[0]})")
    p.add_argument("exchange_dir", help="directory with exchange.json and the grains file")
    p.add_argument("output_dir", help="directory for particles.csv, contacts.csv, status.txt")
    args = p.parse_args(argv)
    try:
        ex = read_exchange(args.exchange_dir)
        cols = read_particles(ex["particles"], ex["pfile"], ex["count"])
        if cols[4] and 4.0 * max(cols[4]) > min(ex["lengths"]):  # one image in reach at most
            raise InputError("exchange.json", "cell.lengths",
                             f"a side shorter than twice the largest diameter ({2.0 * max(cols[4])!r}):"
                             " the nearest-image pair search needs L >= 2 d_max")
    except InputError as e:
        print(f"pydem: error: {e}", file=sys.stderr)
        return 2
    g = dict(zip(("id", "x", "y", "z", "r", "m", "I", "vx", "vy", "vz", "wx", "wy", "wz"), cols))
    g["L"] = ex["lengths"]
    for i in range(len(g["x"])):  # positions into [0, L)
        for key, L in zip("xyz", g["L"]):
            g[key][i] %= L
            if g[key][i] >= L:
                g[key][i] = 0.0
    outdir = args.output_dir
    os.makedirs(outdir, exist_ok=True)
    out = ex["output"]
    status, steps, t, loop = run(ex, g, outdir)
    cell = ",".join(repr(L) for L in g["L"])
    line = f'status={status} cell={cell} steps={steps} time={t!r} loop_time={loop!r} version="{VERSION}"\n'
    if status == "failed":
        print(f"pydem: non-finite position or velocity at step {steps} (t = {t!r})", file=sys.stderr)
        write_atomic(os.path.join(outdir, out["status"]), line)
        return 1
    rows = ["%d,%r,%r,%r,%r,%r,%r,%r,%r,%r,%r,%r\n" % (
        g["id"][i], g["x"][i], g["y"][i], g["z"][i], 2.0 * g["r"][i], g["m"][i],
        g["vx"][i], g["vy"][i], g["vz"][i], g["wx"][i], g["wy"][i], g["wz"][i]) for i in range(len(g["x"]))]
    write_atomic(os.path.join(outdir, out["particles"]),
                 "id,x,y,z,diameter,mass,vx,vy,vz,wx,wy,wz\n" + "".join(rows))
    write_atomic(os.path.join(outdir, out["contacts"]),
                 "i,j,fn,fn_elastic,ft_x,ft_y,ft_z\n" + "".join(contact_rows(g)))
    write_atomic(os.path.join(outdir, out["status"]), line)  # last
    return 0


if __name__ == "__main__":
    sys.exit(main())
