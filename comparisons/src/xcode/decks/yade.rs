//! YADE deck generator: one Python script (`run.py`, run as `yade -n -x run.py`) and the
//! grains (`grains.txt`).
//!
//! Law: `FrictMat` + `Ip2_FrictMat_FrictMat_MindlinPhys(betan=ζ, betas=0)` +
//! `Law2_ScGeom_MindlinPhys_Mindlin`, with `gamma=γ` and `includeAdhesion=True` when the scene's
//! law has `dmt = γ` (engine/src/contact/dmt.rs); for identical materials YADE's kno = (4/3)(E*)√R* with
//! E* = E/(2(1−ν²)), i.e. N = (2/3)Ẽ√R* h^{3/2}: our law with young E = Ẽ(1−ν²), Ẽ = κ^{3/2}.
//! Stress control: a servo in the script (a `PyRunner` every step) integrating our cell
//! dynamics, AR07 (7) M L̈_α = (Ω/L_α)(σ_αα − P) with the strain-rate cap, and imposing
//! `O.cell.velGrad`; `PeriTriaxController` (globUpdate=1, isotropic goal) kept the pressure
//! swinging between 1.01 P and 1.09 P with net forces ~P a² on the xcode-smoke packing and
//! never met the criteria. The script
//! checks the criteria itself every `check_every` steps (net force and torque per body from
//! `O.forces`, diagonal contact stress from `getStress()`, kinetic energy of the fluctuating
//! velocities plus the spin of touching grains) and writes the text export described in
//! `docs/external-formats/yade.md`.

use super::{header_lines, num, Code, Deck, StageKind, Start};
use grainbench_engine::scene::Law;

/// The python literal of a float.
fn py(x: f64) -> String {
    if x.is_infinite() {
        if x > 0.0 {
            "float('inf')".into()
        } else {
            "float('-inf')".into()
        }
    } else if x.is_nan() {
        "float('nan')".into()
    } else {
        num(x)
    }
}

/// The yade deck of `start`.
pub fn deck(start: &Start, deviations: &[String]) -> Deck {
    let (poisson, zeta, gamma) = match start.law() {
        Law::HertzMindlin {
            poisson, zeta, dmt, ..
        } => (*poisson, *zeta, *dmt),
        // Refused by the capability matrix; keep the generator total.
        Law::Linear { zeta, .. } => (0.3, *zeta, None),
    };
    let mut s = String::new();
    for line in header_lines(start, Code::Yade, deviations) {
        s.push_str(&format!("# {line}\n"));
    }
    s.push_str("# Run: yade -n -x run.py (in this directory). Writes final.cell, final.bodies,\n");
    s.push_str("# final.interactions, final.status (docs/external-formats/yade.md).\n\n");
    s.push_str(&format!(
        "N = {}\nLENGTHS = ({})\nPOISSON = {}\nBETAN = {}\nKAPPA0 = {}\n\
         # DMT surface energy γ (pull 4πR*γ in contact; None: no adhesion).\nGAMMA = {}\n\
         # Generalized mass of the cell (AR07 (7)), as in grainbench.\nCELL_MASS = {}\n\
         # Steps between frames of trace.txt (None: no trace).\nTRACE_EVERY = {}\n",
        start.n(),
        start
            .lengths
            .iter()
            .map(|&x| py(x))
            .collect::<Vec<_>>()
            .join(", "),
        py(poisson),
        py(zeta),
        py(start
            .stages
            .first()
            .map_or(start.law().kappa(), |s| s.kappa)),
        gamma.map_or("None".to_string(), py),
        py(grainbench_engine::run::cell_mass(
            &start.scene.numerics,
            start.mass.iter().sum(),
            start.lengths.iter().product(),
            start.dimension,
        )),
        start
            .trace_steps
            .map_or("None".to_string(), |k| k.to_string()),
    ));
    s.push_str("# One dict per DEM stage: kind, pressure (compress), strain-rate cap (1/time),\n");
    s.push_str(
        "# time step, step limit, check period, mu, kappa, tolerances (absolute), and whether\n",
    );
    s.push_str(
        "# a check where only the kinetic criterion fails zeroes the velocities (AR07 §III.A).\n",
    );
    s.push_str("STAGES = [\n");
    for st in &start.stages {
        let (kind, p) = match st.kind {
            StageKind::Compress { pressure } => ("compress", pressure),
            StageKind::FixedVolume { .. } => ("fixed-volume", 0.0),
            StageKind::Aggregate => ("aggregate", 0.0),
        };
        s.push_str(&format!(
            "    dict(kind='{kind}', pressure={}, rate={}, dt={}, max_steps={}, check_every={}, \
             mu={}, kappa={}, tol_force={}, tol_moment={}, tol_stress={}, tol_kinetic={}, \
             quench={}),\n",
            py(p),
            py(st.max_strain_rate),
            py(st.dt),
            st.max_steps,
            st.check_every,
            py(super::mu_number(st.mu)),
            py(st.kappa),
            py(st.tolerances.force),
            py(st.tolerances.moment),
            py(st.tolerances.stress),
            py(st.tolerances.kinetic_per_grain),
            if st.quench { "True" } else { "False" },
        ));
    }
    s.push_str("]\n");
    s.push_str(SCRIPT);

    // Spins (wx wy wz) only for a start with spinning grains.
    let spinning = start.spinning();
    let mut g = String::from(if spinning {
        "# x y z diameter mass vx vy vz wx wy wz\n"
    } else {
        "# x y z diameter mass vx vy vz\n"
    });
    for i in 0..start.n() {
        let p = &start.position[i];
        let v = &start.velocity[i];
        let c = |x: &[f64], a: usize| x.get(a).copied().unwrap_or(0.0);
        g.push_str(&format!(
            "{} {} {} {} {} {} {} {}",
            num(c(p, 0)),
            num(c(p, 1)),
            num(c(p, 2)),
            num(start.diameter[i]),
            num(start.mass[i]),
            num(c(v, 0)),
            num(c(v, 1)),
            num(c(v, 2)),
        ));
        if spinning {
            for w in start.spin3(i) {
                g.push(' ');
                g.push_str(&num(w));
            }
        }
        g.push('\n');
    }
    Deck {
        code: Code::Yade,
        files: vec![("run.py".into(), s), ("grains.txt".into(), g)],
        deviations: deviations.to_vec(),
        args: vec!["-n".into(), "-x".into(), "run.py".into()],
    }
}

/// The fixed part of the script (after the constants).
const SCRIPT: &str = r#"
import math, sys, time

O.reset()
O.periodic = True
O.cell.setBox(*LENGTHS)


def young_of(kappa):
    # Hertz: Ẽ = κ^1.5 (P_ref = 1), E = Ẽ (1 − ν²); YADE's E* = E/(2(1−ν²)) per pair.
    return kappa ** 1.5 * (1.0 - POISSON ** 2)


mat = O.materials.append(FrictMat(young=young_of(KAPPA0), poisson=POISSON,
                                  frictionAngle=math.atan(STAGES[0]['mu'] if STAGES else 0.0),
                                  density=6.0 / math.pi, label='grains'))

with open('grains.txt') as f:
    rows = [l.split() for l in f if l.strip() and not l.startswith('#')]
if len(rows) != N:
    raise RuntimeError('grains.txt: %d grains, expected %d' % (len(rows), N))
for r in rows:
    x, y, z, d, m, vx, vy, vz = [float(v) for v in r[:8]]
    b = utils.sphere((x, y, z), 0.5 * d, material=mat)
    bid = O.bodies.append(b)
    b.state.mass = m
    b.state.inertia = Vector3(1, 1, 1) * (0.1 * m * d * d)
    b.state.vel = Vector3(vx, vy, vz)
    if len(r) == 11:
        b.state.angVel = Vector3(*[float(v) for v in r[8:]])

O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb()]),
    InteractionLoop(
        [Ig2_Sphere_Sphere_ScGeom()],
        [Ip2_FrictMat_FrictMat_MindlinPhys(betan=MatchMaker(algo='val', val=BETAN),
                                           betas=MatchMaker(algo='val', val=0.0),
                                           gamma=GAMMA or 0.0)],
        [Law2_ScGeom_MindlinPhys_Mindlin(includeAdhesion=GAMMA is not None)],
    ),
    # The trace (scene output.trace_every): positions, forces of this step, velocities.
    PyRunner(command='trace()', iterPeriod=TRACE_EVERY or 1, initRun=True,
             dead=TRACE_EVERY is None, label='trace_runner'),
    NewtonIntegrator(damping=0.0),
    # Isotropic stress servo of the cell (AR07 (7)), active in compress stages.
    PyRunner(command='servo()', iterPeriod=1, dead=True, label='servo_runner'),
    # The criteria every check_every steps; pauses the run when they hold (one O.run per
    # stage: O.run(n, True) per check waits ~40 ms each, 570 s for 14168 one-step checks).
    PyRunner(command='check()', iterPeriod=1, dead=True, label='check_runner'),
]

TRACE = []


def trace():
    """One frame of trace.txt (docs/external-formats/yade.md)."""
    if not TRACE:
        TRACE.append(open('trace.txt', 'w'))
        TRACE[0].write('# grainbench trace: `frame ITER TIME LX LY LZ`, then per body: '
                       'id radius mass x y z vx vy vz wx wy wz fx fy fz, then per contact: '
                       '`contact id1 id2 fn tx ty tz` (as final.interactions)\n')
    f = TRACE[0]
    sz = O.cell.size
    f.write('frame %d %r %r %r %r\n' % (O.iter, O.time, sz[0], sz[1], sz[2]))
    for b in O.bodies:
        p, v, w = b.state.pos, b.state.vel, b.state.angVel
        fo = O.forces.f(b.id, True)
        vals = (b.shape.radius, b.state.mass, p[0], p[1], p[2], v[0], v[1], v[2],
                w[0], w[1], w[2], fo[0], fo[1], fo[2])
        f.write('%d %s\n' % (b.id, ' '.join(repr(float(x)) for x in vals)))
    for i in O.interactions:
        if i.isReal:
            t = i.phys.shearForce
            f.write('contact %d %d %r %r %r %r\n' % (i.id1, i.id2,
                    i.phys.normalForce.dot(i.geom.normal), t[0], t[1], t[2]))

# Cell rates L̇_α (leapfrog half-step values), as in grainbench.
LDOT = [0.0, 0.0, 0.0]
SERVO = {'pressure': 0.0, 'rate': 0.0}


def servo():
    """M L̈_α = (Ω/L_α)(σ_αα − P), |L̇_α/L_α| ≤ rate; σ: contact stress (compression
    positive), then velGrad = diag(L̇_α/L_α)."""
    s = utils.getStress()
    size = O.cell.size
    om = size[0] * size[1] * size[2]
    g = [0.0, 0.0, 0.0]
    for a in range(3):
        acc = om / (CELL_MASS * size[a]) * (-s[a, a] - SERVO['pressure'])
        cap = SERVO['rate'] * size[a]
        LDOT[a] = min(max(LDOT[a] + O.dt * acc, -cap), cap)
        g[a] = LDOT[a] / size[a]
    O.cell.velGrad = Matrix3(g[0], 0, 0, 0, g[1], 0, 0, 0, g[2])


def set_law(kappa, mu):
    """Changes κ and μ of the material and of the existing contacts."""
    global KAPPA_NOW
    factor = (kappa / KAPPA_NOW) ** 1.5
    O.materials[mat].young = young_of(kappa)
    O.materials[mat].frictionAngle = math.atan(mu)
    for i in O.interactions:
        if not i.isReal:
            continue
        if factor != 1.0:
            i.phys.kno *= factor
            i.phys.kso *= factor
        i.phys.tangensOfFrictionAngle = math.tan(math.atan(mu))
    KAPPA_NOW = kappa


KAPPA_NOW = KAPPA0


KE_PARTS = [0.0, 0.0]


def measures(st):
    """The criteria of stage st: (ok, all but the kinetic one, max force, max torque, stress
    deviation, KE/grain, σ)."""
    fmax = 0.0
    tmax = 0.0
    for b in O.bodies:
        fmax = max(fmax, O.forces.f(b.id, True).norm())
        tmax = max(tmax, O.forces.t(b.id, True).norm())
    touching = set()
    for i in O.interactions:
        if i.isReal and i.geom.penetrationDepth > 0:
            touching.add(i.id1)
            touching.add(i.id2)
    grad = O.cell.velGrad
    ke_t = 0.0
    ke_r = 0.0
    for b in O.bodies:
        v = b.state.vel - grad * b.state.pos
        ke_t += 0.5 * b.state.mass * v.squaredNorm()
        if b.id in touching:
            w = b.state.angVel
            ke_r += 0.5 * (b.state.inertia[0] * w[0] ** 2 + b.state.inertia[1] * w[1] ** 2
                           + b.state.inertia[2] * w[2] ** 2)
    ke = (ke_t + ke_r) / N
    KE_PARTS[:] = [ke_t / N, ke_r / N]
    s = utils.getStress()  # tension positive, contact part only
    sig = [-s[a, a] for a in range(3)]
    if st['kind'] == 'compress':
        dev = max(abs(x - st['pressure']) for x in sig)
        ok_s = dev <= st['tol_stress']
    else:
        dev = 0.0
        ok_s = True
    rest = fmax <= st['tol_force'] and tmax <= st['tol_moment'] and ok_s
    ok = rest and ke <= st['tol_kinetic']
    return ok, rest, fmax, tmax, dev, ke, sig


def packing_fraction():
    v = sum(4.0 / 3.0 * math.pi * b.shape.radius ** 3 for b in O.bodies)
    return v / O.cell.volume


CHECK = {'stage': None, 'k': 0, 'ok': False, 'last_print': 0.0, 'quenches': 0}


def check():
    """The stage's criteria; a line at most every second (and the last); pause when met."""
    st = CHECK['stage']
    ok, rest, fmax, tmax, dev, ke, sig = measures(st)
    now = time.time()
    if ok or now - CHECK['last_print'] >= 1.0 or O.iter + st['check_every'] > O.stopAtIter:
        CHECK['last_print'] = now
        print('stage %d (%s) step %d t=%.6g phi=%.6f P=%.6g F=%.3g/%.3g M=%.3g/%.3g dS=%.3g/%.3g '
              'KE=%.3g/%.3g (rot %.2g) wall=%.1fs' % (CHECK['k'], st['kind'], O.iter + 1, O.time,
              packing_fraction(), sum(sig) / 3.0, fmax, st['tol_force'], tmax, st['tol_moment'],
              dev, st['tol_stress'], ke, st['tol_kinetic'], KE_PARTS[1], now - t0))
        sys.stdout.flush()
    if ok:
        CHECK['ok'] = True
        O.pause()
    elif rest and st['quench']:
        # AR07 §III.A: every velocity and spin, and the cell's rate, set to zero.
        for b in O.bodies:
            b.state.vel = Vector3.Zero
            b.state.angVel = Vector3.Zero
        LDOT[:] = [0.0, 0.0, 0.0]
        O.cell.velGrad = Matrix3.Zero
        CHECK['quenches'] += 1
        print('grainbench: quench %d at step %d, time %.6g' % (CHECK['quenches'], O.iter + 1, O.time))
        sys.stdout.flush()


statuses = []
t0 = time.time()
for k, st in enumerate(STAGES):
    O.dt = st['dt']
    set_law(st['kappa'], st['mu'])
    if st['kind'] == 'compress':
        SERVO['pressure'] = st['pressure']
        SERVO['rate'] = st['rate']
        servo_runner.dead = False
    else:
        servo_runner.dead = True
        LDOT[:] = [0.0, 0.0, 0.0]
        O.cell.velGrad = Matrix3.Zero
    CHECK.update(stage=st, k=k, ok=False, last_print=0.0, quenches=0)
    check_runner.iterPeriod = st['check_every']
    # Runs after step O.iter's integration: the first check sees check_every steps done.
    check_runner.iterLast = O.iter - 1
    check_runner.dead = False
    O.run(st['max_steps'], True)
    check_runner.dead = True
    status = 'equilibrium' if CHECK['ok'] else 'time-limit'
    statuses.append(status)

# Export (docs/external-formats/yade.md).
grad = O.cell.velGrad
with open('final.cell', 'w') as f:
    sz = O.cell.size
    f.write('lengths %r %r %r\n' % (sz[0], sz[1], sz[2]))
    f.write('iteration %d\n' % O.iter)
    f.write('time %r\n' % O.time)
with open('final.bodies', 'w') as f:
    f.write('# id radius mass x y z vx vy vz wx wy wz\n')
    rows = 0
    for b in O.bodies:
        rows += 1
        v = b.state.vel - grad * b.state.pos  # fluctuating velocity
        p = O.cell.wrap(b.state.pos)
        w = b.state.angVel
        vals = (b.shape.radius, b.state.mass, p[0], p[1], p[2], v[0], v[1], v[2], w[0], w[1], w[2])
        f.write('%d %s\n' % (b.id, ' '.join(repr(float(x)) for x in vals)))
    f.write('# rows %d\n' % rows)  # a file cut short lacks it
with open('final.interactions', 'w') as f:
    # fn: total normal force, repulsive positive; fn_elastic: kno h^1.5;
    # tx ty tz: shear force on id2 (the force on id2 is fn n + t, n from id1 to id2).
    f.write('# id1 id2 fn fn_elastic tx ty tz\n')
    rows = 0
    for i in O.interactions:
        if not i.isReal:
            continue
        rows += 1
        h = i.geom.penetrationDepth
        fn = i.phys.normalForce.dot(i.geom.normal)
        fe = i.phys.kno * max(h, 0.0) ** 1.5
        t = i.phys.shearForce
        f.write('%d %d %r %r %r %r %r\n' % (i.id1, i.id2, fn, fe, t[0], t[1], t[2]))
    f.write('# rows %d\n' % rows)
if TRACE:
    trace()  # the final state closes the series
    TRACE[0].close()
final = 'equilibrium' if statuses and all(s == 'equilibrium' for s in statuses) else 'time-limit'
with open('final.status', 'w') as f:
    f.write(final + '\n')
print('done: %s after %d steps, %.1f s' % (final, O.iter, time.time() - t0))
sys.stdout.flush()
"#;
