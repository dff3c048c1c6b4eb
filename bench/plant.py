"""The plant: rigid body + thruster valves + sensors, advanced in fixed 1 kHz RK4 steps.

In: valve commands (thruster index, on-time) at their delivery time ``t_ns``; faults.
Out: true state (q_BN, omega_BN_B [rad/s], r_N [m], v_N [m/s]), sensor samples on demand
(gyro rates, specific force, star-tracker quaternion), valve status, propellant.
The wrench of the valves is evaluated at the RK4 stage times t, t+h/2, t+h of each step
(DESIGN §6: no adaptive integrator across valve switching). Mass is held at its initial
value during the run (propellant use is reported, not fed back). Deterministic: the
sensors draw from generators spawned from the run seed.
"""

from __future__ import annotations

import numpy as np

from bench.dynamics.rigid_body import MassProperties, make_state, rk4_step
from bench.scenario import Scenario
from bench.sensors.accelerometer import Accelerometer, AccelerometerParams
from bench.sensors.gyro import Gyro, GyroParams
from bench.sensors.rel_nav import RelNav, RelNavParams
from bench.sensors.star_tracker import StarTracker, StarTrackerParams
from bench.valves.thruster_set import ThrusterGeometry, ThrusterSet
from bench.valves.valve import ValveParams

STEP_NS = 1_000_000
NS_PER_S = 1e9


class Plant:
    """Truth model of one vehicle."""

    def __init__(self, sc: Scenario, seed: int, imu_period_ns: int) -> None:
        self.mp = MassProperties(mass_kg=sc.actual.mass_kg, inertia_B_kgm2=sc.actual.inertia_B_kgm2)
        self.state = make_state(sc.q0_BN, sc.omega0_BN_B_rad_s, sc.r0_N_m, sc.v0_N_m_s)
        v = sc.valve
        params = ValveParams(
            max_thrust_N=v.max_thrust_N,
            isp_s=v.isp_s,
            open_delay_s=v.open_delay_s,
            close_delay_s=v.close_delay_s,
            rise_tau_s=v.rise_tau_s,
            tail_tau_s=v.tail_tau_s,
            min_on_s=v.min_on_s,
        )
        self.thrusters = ThrusterSet(
            [ThrusterGeometry(t.r_thr_B_m, t.d_thr_B) for t in sc.thrusters], params
        )
        rng_g, rng_a, rng_s, rng_n = (
            np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(4)
        )
        g = sc.gyro
        self.gyro = Gyro(
            GyroParams(
                arw_rad_sqrt_s=g.arw_rad_sqrt_s,
                bias_rad_s=g.bias_rad_s,
                bias_rw_rad_s_sqrt_s=g.bias_rw_rad_s_sqrt_s,
                lsb_rad_s=g.lsb_rad_s,
                range_rad_s=g.range_rad_s,
                period_s=imu_period_ns / NS_PER_S,
            ),
            rng_g,
        )
        a = sc.accel
        self.accel = Accelerometer(
            AccelerometerParams(
                vrw_m_s_sqrt_s=a.vrw_m_s_sqrt_s,
                bias_m_s2=a.bias_m_s2,
                lsb_m_s2=a.lsb_m_s2,
                range_m_s2=a.range_m_s2,
                period_s=imu_period_ns / NS_PER_S,
            ),
            rng_a,
        )
        s = sc.star_tracker
        self.star = StarTracker(
            StarTrackerParams(
                noise_cross_arcsec=s.noise_cross_arcsec,
                noise_about_arcsec=s.noise_about_arcsec,
                boresight_B=s.boresight_B,
            ),
            rng_s,
        )
        self.rel_nav = (
            RelNav(RelNavParams(sc.rel_nav.noise_pos_m, sc.rel_nav.noise_vel_m_s), rng_n)
            if sc.rel_nav is not None else None
        )
        self.t_ns = 0

    def advance_to(self, t_end_ns: int) -> None:
        """Integrate in fixed steps until ``t_end_ns`` (a multiple of the step)."""
        h = STEP_NS
        h_s = h / NS_PER_S
        thr = self.thrusters
        mp = self.mp
        while self.t_ns < t_end_ns:
            t0 = self.t_ns
            w0, wm, w1 = thr.stage_wrenches(t0, h)
            self.state = rk4_step(self.state, h_s, w0, wm, w1, mp)
            self.t_ns = t0 + h

    def specific_force_B(self) -> tuple[float, float, float]:
        """Non-gravitational acceleration in body axes at the current time [m/s^2]."""
        w = self.thrusters.wrench_B(self.t_ns)
        m = self.mp.mass_kg
        return (w[0] / m, w[1] / m, w[2] / m)
