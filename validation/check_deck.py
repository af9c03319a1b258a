#!/usr/bin/env python3
"""Checks of the validation decks (validation/decks/*.nml) on the outputs of their `agglo` runs.

    check_deck.py CASE RUN_DIRECTORY [RUN_DIRECTORY ...]

reads the run directories (run.nml, bodies_loads.dat, the last field snapshot; docs/outputs.md),
prints one Markdown table row

    | case | reference (citation) | measured | error | tolerance |

and exits with status 1 when the error is outside the stated tolerance (2 on a usage error).
CASE is one of:

sphere_array  one run of a fixed sphere in the periodic cube (a simple-cubic array) driven by a
              uniform body force f to steady state: K = f L^3 / (6 pi mu a U), U the superficial
              velocity (the flux through the x-face plane i = nx, which the sphere never cuts, over
              its area, from the last field snapshot), against Zick & Homsy (1982, J. Fluid Mech. 115,
              13, Table 2) K = 4.292 at phi = 0.125 (2.810 at 0.064, 2.008 at 0.027).
rotating      runs of a sphere turning at Omega about z in boxes of several sizes: the steady torque
              T of the last step over 8 pi mu a^3 Omega (Stokes, unbounded), extrapolated to a/L = 0
              by a least-squares line in (a/L)^3 (the periodic images' correction), against 1.
oscillating   one run of a sphere oscillating along x, c0 + A sin(omega t): the x force fitted over
              the last whole period by a cos(omega t) + b sin(omega t) + c (the load of step n at the
              middle of the step), F = a - i b, against Stokes' (1851) force on a sphere in
              translational oscillation (Landau & Lifshitz, Fluid Mechanics, section 24, problem 5)
              with the periodic box's mean-flow correction; error of the amplitude (the phase is
              printed beside it and held to 4 degrees).
settling      one run of a free sphere settling under gravity in the periodic cube (&scene particles =
              'free', &pair gravity): at the last step K = W / (6 pi mu a U_s), W = (rho_p - rho_f) V g
              the net weight, U_s = U_p - U_face the slip (U_p from particles.h5, U_face the flux
              through the box's x-face i = nx over its area, from the last field snapshot), against
              Zick & Homsy (1982) as for sphere_array, within 1% (test_free_settling's bound).
released      one run of a free sphere started at U_0 along x in fluid at rest: U_p(t) / U_0 of every
              fluid step (particles.h5) against the unsteady Stokes decay with added mass and Basset
              history (Maxey & Riley 1983, Phys. Fluids 26, 883; docs/theory.md, "A sphere released
              in fluid at rest"), U(0+) = m U_0 / (m + m_f / 2), evaluated from its closed Laplace
              transform (Basset 1888) on Talbot's contour (Abate & Valko 2004): the largest
              |U_p - U_ref| / U_0 over the run, U_p / U_ref - 1 over [0.05 tau_p, end] and the distance
              travelled, each within 5% (test_free_release's bounds).
"""
import math
import re
import sys
from pathlib import Path

import h5py
import numpy as np

# Zick & Homsy 1982, J. Fluid Mech. 115, 13, Table 2: K of a simple-cubic array of spheres.
ZICK_HOMSY = {0.027: 2.008, 0.064: 2.810, 0.125: 4.292}


def read_namelist(path):
    """The resolved deck run.nml as {'GROUP': {'VARIABLE': [values as text]}} (repeats n*v expanded)."""
    groups, group, name = {}, None, None
    for line in Path(path).read_text().splitlines():
        line = line.strip()
        if not line or line.startswith('!'):
            continue
        if line.startswith('&'):
            group = groups.setdefault(line[1:].upper(), {})
            continue
        if line == '/':
            group = None
            continue
        match = re.match(r'([A-Za-z_][A-Za-z0-9_]*)(\([^)]*\))?\s*=(.*)', line)
        if match:
            name, text = match.group(1).upper(), match.group(3)
            group[name] = []
        else:
            text = line
        for item in re.findall(r'"[^"]*"|\'[^\']*\'|[^,\s]+', text):
            count, star, value = item.partition('*') if not item.startswith(('"', "'")) else ('', '', item)
            if star:
                group[name].extend([value] * int(count))
            else:
                group[name].append(item)
    return groups


def number(deck, group, variable, index=0):
    return float(deck[group][variable][index].replace('D', 'E').replace('d', 'e'))


def read_loads(run):
    """bodies_loads.dat as an array (rows, 25 columns): step, time, body, force, torque, ..."""
    return np.loadtxt(Path(run) / 'bodies_loads.dat', comments='#', ndmin=2)


def last_field(run):
    snapshots = sorted(Path(run).glob('fields_*.h5'))
    if not snapshots:
        raise SystemExit(f'check_deck: no field snapshot in {run}')
    return h5py.File(snapshots[-1], 'r')


def one_body_run(run):
    """The resolved deck of a one-body run, its fluid density, dynamic viscosity and body radius."""
    deck = read_namelist(Path(run) / 'run.nml')
    rho = number(deck, 'FLUID', 'DENSITY')
    return deck, rho, number(deck, 'FLUID', 'VISCOSITY') * rho, number(deck, 'BODIES', 'RADIUS')


def row(case, reference, measured, error, tolerance, inside):
    print(f'| {case} | {reference} | {measured} | {error} | {tolerance} |', flush=True)
    return 0 if inside else 1


def sphere_array(runs):
    run = runs[0]
    deck = read_namelist(Path(run) / 'run.nml')
    mu = number(deck, 'FLUID', 'VISCOSITY') * number(deck, 'FLUID', 'DENSITY')
    radius = number(deck, 'BODIES', 'RADIUS')
    drive = number(deck, 'BODIES', 'DRIVING_FORCE')
    lengths = [number(deck, 'GRID', f'LENGTH_{c}') for c in 'XYZ']
    cells = int(deck['GRID']['NX'][0])
    phi = 4.0 / 3.0 * math.pi * radius**3 / math.prod(lengths)
    near = min(ZICK_HOMSY, key=lambda p: abs(p - phi))
    if abs(phi / near - 1) > 1e-3:
        raise SystemExit(f'check_deck: phi = {phi:.4f} is not one of Zick & Homsy\'s {sorted(ZICK_HOMSY)}')
    with last_field(run) as fields:
        u = fields['fields/u'][()]   # (nz, ny, nx): u[:, :, nx - 1] is the plane i = nx
    velocity = u[:, :, -1].mean()
    force = drive * math.prod(lengths)
    k = force / (6 * math.pi * mu * radius * velocity)
    loads = read_loads(run)
    load = loads[-1, 3]
    print(f'sphere_array: D/dx {2 * radius / (lengths[0] / cells):.2f}, U = {velocity:.10e} m/s, '
          f'K = {k:.16g}, steps {int(loads[-1, 0])}, load / (f L^3) - 1 = {load / force - 1:.2e}', file=sys.stderr)
    reference = ZICK_HOMSY[near]
    error = k / reference - 1
    tolerance = 0.05
    # At steady state the momentum-balance load equals the drive on the cell, f L^3.
    steady = abs(load / force - 1) < 1e-6
    return row(f'sphere array, phi = {near}, D/dx {2 * radius * cells / lengths[0]:.2f}',
               f'K = {reference} (Zick & Homsy 1982, Table 2)', f'K = {k:.4f}', f'{100 * error:+.2f}%',
               f'5% (load = f L^3 to 1e-6: {"yes" if steady else "no"})', abs(error) <= tolerance and steady)


def rotating(runs):
    x, y = [], []
    for run in runs:
        deck = read_namelist(Path(run) / 'run.nml')
        mu = number(deck, 'FLUID', 'VISCOSITY') * number(deck, 'FLUID', 'DENSITY')
        radius = number(deck, 'BODIES', 'RADIUS')
        omega = number(deck, 'BODIES', 'ANGULAR_VELOCITY', 2)
        length = number(deck, 'GRID', 'LENGTH_X')
        cells = int(deck['GRID']['NX'][0])
        torque = read_loads(run)[-1, 8]
        ratio = -torque / (8 * math.pi * mu * radius**3 * omega)
        print(f'rotating: {cells}^3, D/dx {2 * radius * cells / length:.2f}, a/L {radius / length:.4f}, '
              f'T / (8 pi mu a^3 Omega) = {ratio:.8f}', file=sys.stderr)
        x.append((radius / length)**3)
        y.append(ratio)
    slope, unbounded = np.polyfit(x, y, 1)
    print(f'rotating: extrapolated {unbounded:.8f}, slope {slope:.4f}', file=sys.stderr)
    error = unbounded - 1
    tolerance = 0.05
    boxes = ', '.join(f'{1 / (2 * math.cbrt(v)):.0f}' for v in x)
    return row(f'rotating sphere, D/dx {2 * radius * cells / length:.2f}, boxes L/D = {boxes}',
               'T = 8 pi mu a^3 Omega (Stokes)', f'T / (8 pi mu a^3 Omega) = {unbounded:.4f} (extrapolated)',
               f'{100 * error:+.2f}%', '5%', abs(error) <= tolerance)


def stokes_oscillating_force(radius, omega, velocity, box_length, mu, rho):
    """Stokes' force for the velocity velocity e^{i omega t}, with the periodic box's mean-flow
    correction F = -S U / (1 + S / (i omega M) + rho V / M), M = rho (L^3 - V) (box_length > 0)."""
    nu = mu / rho
    lam = (1 + 1j) * math.sqrt(omega / (2 * nu))
    s = 6 * math.pi * mu * radius * (1 + lam * radius + lam**2 * radius**2 / 9)
    force = -s * velocity
    if box_length > 0:
        volume = 4 / 3 * math.pi * radius**3
        fluid_mass = rho * (box_length**3 - volume)
        force = force / (1 + s / (1j * omega * fluid_mass) + rho * volume / fluid_mass)
    return force


def oscillating(runs):
    run = runs[0]
    deck, rho, mu, radius = one_body_run(run)
    amplitude = number(deck, 'BODIES', 'OSCILLATION_AMPLITUDE')
    frequency = number(deck, 'BODIES', 'OSCILLATION_FREQUENCY')
    length = number(deck, 'GRID', 'LENGTH_X')
    dt = number(deck, 'RUN', 'DT')
    loads = read_loads(run)
    steps = loads[:, 0].astype(int)
    force = loads[:, 3]
    omega = 2 * math.pi * frequency
    per_period = round(1 / (frequency * dt))
    if abs(per_period * dt * frequency - 1) > 1e-9 or len(steps) < per_period + 2:
        raise SystemExit('check_deck: oscillating needs dt = period / whole number and at least one period')
    last = slice(len(steps) - per_period, len(steps))
    t = (steps[last] - 0.5) * dt
    a = 2 * np.sum(force[last] * np.cos(omega * t)) / per_period
    b = 2 * np.sum(force[last] * np.sin(omega * t)) / per_period
    measured = complex(a, -b)
    reference = stokes_oscillating_force(radius, omega, amplitude * omega, length, mu, rho)
    error = abs(measured) / abs(reference) - 1
    phase = math.degrees(np.angle(measured / reference))
    print(f'oscillating: |F| = {abs(measured):.10e} N, reference {abs(reference):.10e} N, amplitude error '
          f'{100 * error:.4f}%, phase {phase:.4f} deg, {len(steps) // per_period} periods of {per_period} steps',
          file=sys.stderr)
    return row(f'oscillating sphere, D/dx {2 * radius / (length / int(deck["GRID"]["NX"][0])):.1f}, L = '
               f'{length / radius:.0f} R, A = {amplitude / radius:.3f} R',
               'Stokes 1851 with the box correction (Landau & Lifshitz §24)',
               f'amplitude {abs(measured):.4e} N, phase {phase:+.2f} deg', f'{100 * error:+.2f}%',
               '3%, phase 4 deg', abs(error) <= 0.03 and abs(phase) <= 4.0)


def settling(runs):
    run = runs[0]
    deck, rho, mu, radius = one_body_run(run)
    density = number(deck, 'PAIR', 'DENSITY')
    gravity = np.array([number(deck, 'PAIR', 'GRAVITY', i) for i in range(3)])
    lengths = [number(deck, 'GRID', f'LENGTH_{c}') for c in 'XYZ']
    cells = int(deck['GRID']['NX'][0])
    volume = 4.0 / 3.0 * math.pi * radius**3
    phi = volume / math.prod(lengths)
    near = min(ZICK_HOMSY, key=lambda p: abs(p - phi))
    if abs(phi / near - 1) > 1e-3 or gravity[1] != 0 or gravity[2] != 0:
        raise SystemExit(f'check_deck: settling needs phi of Zick & Homsy ({sorted(ZICK_HOMSY)}) and gravity along x')
    weight = (density - rho) * volume * gravity[0]
    with h5py.File(Path(run) / 'particles.h5', 'r') as particles:
        particle_time = particles['time'][-1]
        velocity = particles['particle1/velocity'][-1]
    with last_field(run) as fields:
        field_time = fields['time'][()]
        face = fields['fields/u'][()][:, :, -1].mean()
    if abs(particle_time - field_time) > 1e-9 * field_time:
        raise SystemExit(f'check_deck: particles.h5 ends at t = {particle_time}, the last field at {field_time}')
    slip = velocity[0] - face
    k = weight / (6 * math.pi * mu * radius * slip)
    print(f'settling: D/dx {2 * radius * cells / lengths[0]:.2f}, U_p = {velocity[0]:.10e}, U_face = {face:.10e}, '
          f'slip = {slip:.16g} m/s, K = {k:.16g}', file=sys.stderr)
    reference = ZICK_HOMSY[near]
    error = k / reference - 1
    return row(f'settling sphere, phi = {near}, D/dx {2 * radius * cells / lengths[0]:.2f}, '
               f'rho_p/rho_f {density / rho:.2f}', f'K = {reference} (Zick & Homsy 1982, Table 2)',
               f'K = {k:.4f}', f'{100 * error:+.2f}%', '1%', abs(error) <= 0.01)


def release_decay(time, radius, density, fluid_density, mu, terms=24):
    """U(t) / U(0+) of the released sphere: the inverse of U~(s) / U(0+) = 1 / (s + gamma sqrt(pi) sqrt(s)
    + beta), beta = 6 pi mu a / m_e, gamma = 6 a^2 sqrt(pi rho_f mu) / m_e, m_e = (rho_p + rho_f / 2) V
    (Basset 1888; Maxey & Riley 1983), on Talbot's fixed contour with terms nodes (Abate & Valko 2004,
    Int. J. Numer. Meth. Eng. 60, 979); time > 0."""
    effective_mass = (density + 0.5 * fluid_density) * 4.0 / 3.0 * math.pi * radius**3
    beta = 6 * math.pi * mu * radius / effective_mass
    gamma = 6 * radius**2 * math.sqrt(math.pi * fluid_density * mu) / effective_mass

    def transform(s):
        return 1 / (s + gamma * math.sqrt(math.pi) * np.sqrt(s) + beta)

    r = 2 * terms / (5 * time)
    total = 0.5 * np.exp(r * time) * transform(complex(r, 0)).real
    for k in range(1, terms):
        theta = k * math.pi / terms
        cot = math.cos(theta) / math.sin(theta)
        s = r * theta * complex(cot, 1)
        sigma = theta + (theta * cot - 1) * cot
        total += (np.exp(time * s) * transform(s) * complex(1, sigma)).real
    return total * r / terms


def released(runs):
    run = runs[0]
    deck, rho, mu, radius = one_body_run(run)
    density = number(deck, 'PAIR', 'DENSITY')
    start = number(deck, 'BODIES', 'VELOCITY')
    length = number(deck, 'GRID', 'LENGTH_X')
    cells = int(deck['GRID']['NX'][0])
    if any(number(deck, 'PAIR', 'GRAVITY', i) != 0 for i in range(3)):
        raise SystemExit('check_deck: released needs no gravity')
    with h5py.File(Path(run) / 'particles.h5', 'r') as particles:
        time = particles['time'][()]
        velocity = particles['particle1/velocity'][:, 0] / start
    tau = 2 * density * radius**2 / (9 * mu)
    jump = density / (density + 0.5 * rho)   # U(0+) / U_0
    reference = np.array([1.0] + [jump * release_decay(t, radius, density, rho, mu) for t in time[1:]])
    largest = np.max(np.abs(velocity[1:] - reference[1:]))
    late = time >= 0.05 * tau
    late_relative = np.max(np.abs(velocity[late] / reference[late] - 1))
    # Distance by the trapezoid rule; the first interval from U(0+) (the jump is instantaneous).
    dt = np.diff(time)
    travelled = np.sum(0.5 * (velocity[:-1] + velocity[1:]) * dt) + 0.5 * (jump - 1) * dt[0]
    expected = np.sum(0.5 * (reference[:-1] + reference[1:]) * dt) + 0.5 * (jump - 1) * dt[0]
    displacement = travelled / expected - 1
    print(f'released: D/dx {2 * radius * cells / length:.2f}, L/D {length / (2 * radius):.1f}, {len(time) - 1} rows '
          f'to t / tau_p = {time[-1] / tau:.4f}; U_p/U_0 rows 1-3 {velocity[1]:.16g} {velocity[2]:.16g} '
          f'{velocity[3]:.16g} (reference {reference[1]:.6f} {reference[2]:.6f} {reference[3]:.6f}); '
          f'last U_p/U_0 = {velocity[-1]:.16g}; max |U_p - U_ref| / U_0 = {largest:.6f}, '
          f'late relative {late_relative:.6f}, displacement {displacement:+.6f}', file=sys.stderr)
    inside = largest <= 0.05 and late_relative <= 0.05 and abs(displacement) <= 0.05
    return row(f'released sphere, D/dx {2 * radius * cells / length:.1f}, L = {length / (2 * radius):.0f} D, '
               f'rho_p/rho_f {density / rho:.2f}, over tau_p',
               'unsteady Stokes with added mass and history (Maxey & Riley 1983)',
               f'max U_p/U_0 - ref {100 * largest:.2f}%, late {100 * late_relative:.2f}%, '
               f'distance {100 * displacement:+.2f}%', f'{100 * largest:.2f}% of U_0', '5% each', inside)


CASES = {'sphere_array': sphere_array, 'rotating': rotating, 'oscillating': oscillating, 'settling': settling, 'released': released}

if __name__ == '__main__':
    if len(sys.argv) < 3 or sys.argv[1] not in CASES:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    sys.exit(CASES[sys.argv[1]](sys.argv[2:]))
