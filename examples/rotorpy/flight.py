"""A closed-loop flight of RotorPy's multirotor (UPenn, `pip install rotorpy`), written as a
contract CSV: a third source of truth, from another group's simulator.

Not part of the product or its tests (it needs RotorPy and its dependencies; see README.md
here). RotorPy's own aerodynamic model (rotor drag k_d Omega v
at each hub, induced inflow k_z Omega w, translational lift k_h V_h^2, parasitic drag
-|v| C_D v, flapping moments k_flap) is the truth; hidden effects are switched on through
RotorPy's own parameters where it has them (drag, flapping, wind, CG via rotor positions)
and, for a weak rotor, by scaling one rotor's thrust in its wrench.

usage: python flight.py CASE SEED OUT.csv [--noise K] [--T SECONDS] [--surface]
CASE: clean, drag, drag_hb, cg, weak, flap or wind. Vehicle: data/vehicles/rotorpy_hummingbird.toml.
"""
import sys, copy
import numpy as np
from scipy.spatial.transform import Rotation
from rotorpy.vehicles.multirotor import Multirotor
from rotorpy.vehicles.hummingbird_params import quad_params as HB
from rotorpy.controllers.quadrotor_control import SE3Control

case, seed, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
noise_k = float(sys.argv[sys.argv.index('--noise') + 1]) if '--noise' in sys.argv else 1.0
T = float(sys.argv[sys.argv.index('--T') + 1]) if '--T' in sys.argv else 60.0
rate = 200.0
rng = np.random.default_rng(seed)
# White noise (times --noise) on velocity m/s, rates rad/s, rotor speeds rad/s, force N,
# moment N m.
SIG = dict(v=0.02, w=0.005, om=0.5, f=0.03, m=0.0015)
HEADER = 't,u,v,w,p,q,r,omega_1,omega_2,omega_3,omega_4,fx,fy,fz,mx,my,mz,qw,qx,qy,qz'
# ENU from NED axes (and back): swap x and y, flip z.
ENU_NED = np.array([[0, 1, 0], [1, 0, 0], [0, 0, -1]])
FLU_FRD = np.diag([1, -1, -1])

nominal = copy.deepcopy(HB)
nominal['c_Dx'] = nominal['c_Dy'] = nominal['c_Dz'] = 0.0  # clean airframe
truth = copy.deepcopy(nominal)
wind = np.zeros(3)
weak = None
if case == 'clean':
    pass
elif case == 'drag':  # RotorPy's parasitic drag, 4x the hummingbird's
    truth['c_Dx'], truth['c_Dy'], truth['c_Dz'] = 0.02, 0.02, 0.04
elif case == 'drag_hb':  # the hummingbird's own parasitic drag
    truth['c_Dx'], truth['c_Dy'], truth['c_Dz'] = 0.5e-2, 0.5e-2, 1e-2
elif case == 'cg':  # CG 15 mm forward, 8 mm right of the rotor centroid (FRD)
    off = np.array([0.015, -0.008, 0.0])  # FLU: forward +x, right = -y
    truth['rotor_pos'] = {k: v - off for k, v in nominal['rotor_pos'].items()}
elif case == 'weak':
    weak = (int(rng.integers(0, 4)), 0.9)
elif case == 'flap':
    truth['k_flap'] = 2.0e-5
elif case == 'wind':
    wind = np.array([2.0, -1.0, 0.0])
else:
    raise SystemExit('unknown case ' + case)


class Truth(Multirotor):
    def compute_body_wrench(self, body_rates, rotor_speeds, body_airspeed_vector):
        if weak is None:
            return super().compute_body_wrench(body_rates, rotor_speeds, body_airspeed_vector)
        i, s = weak
        # thrust of rotor i scaled by s: the same wrench with that rotor's k_eta and k_h scaled
        F, M = super().compute_body_wrench(body_rates, rotor_speeds, body_airspeed_vector)
        la = body_airspeed_vector + np.cross(body_rates, self.rotor_geometry[i])
        Ti = self.k_eta * rotor_speeds[i] ** 2 + self.k_h * (la[0] ** 2 + la[1] ** 2)
        dF = np.array([0, 0, (s - 1) * Ti])
        dM = np.cross(self.rotor_geometry[i], dF)
        return F + dF, M + dM


# A smooth random trajectory: sums of sines in x, y, z and yaw (flat outputs to snap).
class Multisine:
    def __init__(self):
        self.terms = []
        for ax, (amp, fmin, fmax, n) in enumerate([(10.0, 0.04, 0.12, 3), (10.0, 0.04, 0.12, 3),
                                                  (1.5, 0.05, 0.2, 2), (2.0, 0.02, 0.08, 2)]):
            for _ in range(n):
                f = rng.uniform(fmin, fmax) * 2 * np.pi
                self.terms.append((ax, amp / n * rng.uniform(0.6, 1.0), f, rng.uniform(0, 2 * np.pi)))

    def update(self, t):
        d = np.zeros((5, 4))
        for ax, a, f, ph in self.terms:
            for k in range(5):
                # d^k/dt^k of a sin(f t + ph) minus its value at t = 0 (start at the origin)
                d[k, ax] += a * f ** k * np.sin(f * t + ph + k * np.pi / 2)
                if k == 0:
                    d[k, ax] -= a * np.sin(ph)
        return {'x': d[0, :3], 'x_dot': d[1, :3], 'x_ddot': d[2, :3], 'x_dddot': d[3, :3],
                'x_ddddot': d[4, :3], 'yaw': d[0, 3], 'yaw_dot': d[1, 3], 'yaw_ddot': d[2, 3]}


def noise(sigma, size=None):
    return noise_k * rng.normal(scale=sigma, size=size)


def row(t, v, w, omega, F, M, R):
    """A contract row from RotorPy's body FLU velocity v, rates w, rotor speeds, wrench
    and body(FLU)->world(ENU) rotation R, with the sensors' noise: FRD flips y and z,
    the attitude is body(FRD)->NED."""
    v, w, F, M = (FLU_FRD @ x for x in (v, w, F, M))
    q = Rotation.from_matrix(ENU_NED @ R @ FLU_FRD).as_quat()  # x y z w
    return [t, *(v + noise(SIG['v'], 3)), *(w + noise(SIG['w'], 3)),
            *(omega + noise(SIG['om'], 4)), *(F + noise(SIG['f'], 3)), *(M + noise(SIG['m'], 3)),
            q[3], q[0], q[1], q[2]]


def write(rows):
    np.savetxt(out, np.array(rows), delimiter=',', header=HEADER, comments='', fmt='%.7g')


hover = np.sqrt(nominal['mass'] * 9.81 / 4 / nominal['k_eta'])

if '--surface' in sys.argv:
    # A response-surface set instead of a flight: 3000 random states and rotor speeds,
    # the wrench of each (no dynamics, no controller), t numbering the rows.
    veh = Truth(truth, control_abstraction='cmd_motor_speeds', aero=True)
    rows = []
    for k in range(3000):
        vb = rng.uniform([-8, -8, -3], [8, 8, 3])
        w = rng.uniform([-3, -3, -1.5], [3, 3, 1.5])
        om = hover * rng.uniform(0.75, 1.3, 4)
        q = Rotation.from_euler('xyz', rng.uniform([-0.5, -0.5, -np.pi], [0.5, 0.5, np.pi])).as_quat()
        R = Rotation.from_quat(q).as_matrix()
        air = vb - R.T @ wind
        F, M = veh.compute_body_wrench(w, om, air)
        rows.append(row(k, vb, w, om, F, M, R))
    write(rows)
    print(f'{out}: response surface, 3000 points, weak={weak}')
    sys.exit(0)

traj = Multisine()
ctrl = SE3Control(nominal)
f0 = traj.update(0.0)
state = {'x': np.zeros(3), 'v': f0['x_dot'].copy(), 'q': Rotation.from_euler('z', f0['yaw']).as_quat(),
         'w': np.zeros(3), 'wind': wind.copy(), 'rotor_speeds': hover * np.ones(4)}
veh = Truth(truth, initial_state=state, control_abstraction='cmd_motor_speeds', aero=True)
# Excitation on each rotor command: a multisine, 0.3-6 Hz, about 4 % of hover speed.
ex = [(rng.uniform(0.3, 6.0) * 2 * np.pi, rng.uniform(0, 2 * np.pi), j) for j in range(4) for _ in range(6)]

dt = 1 / rate
rows = []
for k in range(int((T + 2) * rate)):
    t = k * dt
    st = state
    R = Rotation.from_quat(st['q']).as_matrix()
    vb = R.T @ (st['v'] - wind)  # air-relative in body FLU
    vg = R.T @ st['v']           # what a user logs: ground velocity in body axes
    F, M = veh.compute_body_wrench(st['w'], st['rotor_speeds'], vb)
    if t >= 2.0:  # the first 2 s settle the start's transient
        rows.append(row(t - 2.0, vg, st['w'], st['rotor_speeds'], F, M, R))
    flat = traj.update(t)
    u = ctrl.update(t, st, flat)
    cmd = u['cmd_motor_speeds'] + sum(0.04 * hover / 6 * np.sin(f * t + ph) * np.eye(4)[j] for f, ph, j in ex)
    state = veh.step(st, {'cmd_motor_speeds': cmd}, dt)
    if not np.all(np.isfinite(state['x'])) or np.linalg.norm(state['x'] - flat['x']) > 5:
        raise SystemExit(f'diverged at t={t:.2f}')

write(rows)
a = np.array(rows)
sp = np.linalg.norm(a[:, 1:4], axis=1)
print(f'{out}: {len(rows)} rows, speed max {sp.max():.1f} mean {sp.mean():.1f} m/s, '
      f'|r| max {np.abs(a[:, 6]).max():.2f} rad/s, Omega {a[:, 7:11].min():.0f}-{a[:, 7:11].max():.0f}, weak={weak}')
