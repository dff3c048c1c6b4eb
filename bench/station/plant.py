"""The plant: rigid body + thruster valves + sensors, advanced in fixed 1 kHz RK4 steps.

In: valve commands (thruster index, on-time) at their delivery time ``t_ns``; faults.
Out: true state (q_BN, omega_BN_B [rad/s], r_N [m], v_N [m/s]), sensor samples on demand
(gyro rates, specific force, star-tracker quaternion), valve status, propellant.
The wrench of the valves is evaluated at the RK4 stage times t, t+h/2, t+h of each step
(DESIGN §6: no adaptive integrator across valve switching). Mass is held at its initial
value during the run (propellant use is reported, not fed back). Deterministic: the
sensors draw from generators spawned from the run seed.

Optional models (scenario tables; absent = the historical plant, bit-identical, on the
fast ``rk4_step``): disturbance force/torque (``bench.station.environment.disturbance``),
gravity-gradient torque (``bench.station.environment.gravity_gradient``), HCW relative
translation (``bench.station.dynamics.hcw``; r, v then relative to the leader in its Hill
frame) — these switch to ``bench.station.dynamics.stepper.rk4_step_env``, which samples them at
every RK4 stage; ``capture`` events (``bench.station.dynamics.capture``) change the mass
properties at the first step boundary at or after their time; the throttled valve
model (``bench.station.valves.throttled``) replaces the on-off valves. The accelerometer's
specific force includes the disturbance force (a non-gravitational force).

Truth the flight software is not told (a campaign's dispersions; absent = nominal): each
thruster's ``thrust_scale`` and actual direction, and the centre-of-mass offset
(``ThrusterSet.set_com_offset``; a capture event's centre of mass replaces it).
"""

from __future__ import annotations

import numpy as np

from bench.scenario.spec import CaptureSpec, Scenario
from bench.station.dynamics.capture import capture_state
from bench.station.dynamics.hcw import HcwParams, HcwTranslation
from bench.station.dynamics.rigid_body import MassProperties, make_state, rk4_step
from bench.station.dynamics.stepper import rk4_step_env
from bench.station.dynamics.translation import InertialTranslation, TranslationModel
from bench.station.environment.base import EnvironmentModel
from bench.station.environment.disturbance import Disturbance
from bench.station.environment.gravity_gradient import GravityGradient, GravityGradientParams
from bench.station.sensors.accelerometer import Accelerometer, AccelerometerParams
from bench.station.sensors.gyro import Gyro, GyroParams
from bench.station.sensors.rel_nav import RelNav, RelNavParams
from bench.station.sensors.star_tracker import StarTracker, StarTrackerParams
from bench.station.valves.base import ValveModel
from bench.station.valves.params import ValveParams
from bench.station.valves.throttled import ThrottledValve
from bench.station.valves.thruster_set import ThrusterGeometry, ThrusterSet

STEP_NS = 1_000_000
NS_PER_S = 1e9


class Plant:
    """Truth model of one vehicle."""

    def __init__(
        self, sc: Scenario, seed: int, imu_period_ns: int, control_period_ns: int | None = None
    ) -> None:
        """``control_period_ns``: the command period, needed by the throttled valve model."""
        self.mp = MassProperties(mass_kg=sc.actual.mass_kg, inertia_B_kgm2=sc.actual.inertia_B_kgm2)
        self.state = make_state(sc.q0_BN, sc.omega0_BN_B_rad_s, sc.r0_N_m, sc.v0_N_m_s)
        v = sc.valve
        params = [
            ValveParams(
                max_thrust_N=m,
                isp_s=v.isp_s,
                open_delay_s=v.open_delay_s,
                close_delay_s=v.close_delay_s,
                rise_tau_s=v.rise_tau_s,
                tail_tau_s=v.tail_tau_s,
                min_on_s=v.min_on_s,
            )
            for m in sc.actual_max_thrusts_N
        ]
        factory = None
        if v.model == "throttled":
            if control_period_ns is None:
                raise ValueError("the throttled valve model needs control_period_ns")
            period = control_period_ns

            def factory(p: ValveParams, rng: np.random.Generator | None) -> ValveModel:
                return ThrottledValve(p, period, rng)

        self.thrusters = ThrusterSet(
            [ThrusterGeometry(t.r_thr_B_m, t.d_thr_B if t.actual_d_thr_B is None
                              else t.actual_d_thr_B) for t in sc.thrusters],
            params,
            valve_factory=factory,
        )
        if sc.actual.com_offset_B_m != (0.0, 0.0, 0.0):
            self.thrusters.set_com_offset(sc.actual.com_offset_B_m)
        self.translation: TranslationModel = (
            HcwTranslation(HcwParams(sc.dynamics.orbit_radius_m))
            if sc.dynamics.translation == "hcw" else InertialTranslation()
        )
        self.disturbance = (
            Disturbance(sc.disturbance, self.translation)
            if sc.disturbance is not None and not sc.disturbance.is_zero else None
        )
        env: list[EnvironmentModel] = []
        if self.disturbance is not None:
            env.append(self.disturbance)
        if sc.environment.gravity_gradient:
            env.append(GravityGradient(GravityGradientParams(sc.environment.orbit_radius_m)))
        self.environment: tuple[EnvironmentModel, ...] = tuple(env)
        self.use_env_stepper = bool(env) or sc.dynamics.translation != "inertial"
        self.pending_events: list[tuple[int, CaptureSpec]] = [
            (-(-round(e.t_s * NS_PER_S) // STEP_NS) * STEP_NS, e) for e in sc.events
        ]
        self.applied_events: list[tuple[int, CaptureSpec]] = []
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

    def next_event_ns(self) -> int | None:
        """Step time of the next scheduled mass-property event, None if none is pending."""
        return self.pending_events[0][0] if self.pending_events else None

    def _apply_due_events(self) -> None:
        while self.pending_events and self.pending_events[0][0] <= self.t_ns:
            _t_ev, e = self.pending_events.pop(0)
            self.apply_capture(e)
            self.applied_events.append((self.t_ns, e))

    def apply_capture(self, e: CaptureSpec) -> None:
        """Change the mass properties now (``station.dynamics.capture``; momentum conserved)."""
        mp_new = MassProperties(mass_kg=e.mass.mass_kg, inertia_B_kgm2=e.mass.inertia_B_kgm2)
        c0 = self.thrusters.com_B_m
        delta = (e.com_B_m[0] - c0[0], e.com_B_m[1] - c0[1], e.com_B_m[2] - c0[2])
        self.state = capture_state(
            self.state, self.t_ns / NS_PER_S, self.mp, mp_new, delta, self.translation
        )
        self.mp = mp_new
        self.thrusters.set_com_offset(e.com_B_m)

    def advance_to(self, t_end_ns: int) -> None:
        """Integrate in fixed steps until ``t_end_ns`` (a multiple of the step).

        Scheduled mass-property events are applied at their step boundary (also at
        ``t_end_ns`` itself, so the state at the end reflects them).
        """
        h = STEP_NS
        h_s = h / NS_PER_S
        thr = self.thrusters
        if self.pending_events:
            self._apply_due_events()
        while self.t_ns < t_end_ns:
            t0 = self.t_ns
            w0, wm, w1 = thr.stage_wrenches(t0, h)
            if self.use_env_stepper:
                self.state = rk4_step_env(
                    self.state, t0 / NS_PER_S, h_s, w0, wm, w1, self.mp,
                    self.translation, self.environment,
                )
            else:
                self.state = rk4_step(self.state, h_s, w0, wm, w1, self.mp)
            self.t_ns = t0 + h
            if self.pending_events:
                self._apply_due_events()

    def specific_force_B(self) -> tuple[float, float, float]:
        """Non-gravitational acceleration in body axes at the current time [m/s^2].

        Thrust plus the disturbance force (HCW and gravity-gradient terms are
        gravitational: an accelerometer does not sense them).
        """
        w = self.thrusters.wrench_B(self.t_ns)
        fx, fy, fz = w[0], w[1], w[2]
        if self.disturbance is not None:
            s = self.state
            d = self.disturbance.wrench_B(self.t_ns / NS_PER_S, (s[0], s[1], s[2], s[3]), self.mp)
            fx, fy, fz = fx + d[0], fy + d[1], fz + d[2]
        m = self.mp.mass_kg
        return (fx / m, fy / m, fz / m)
