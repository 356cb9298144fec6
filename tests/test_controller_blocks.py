"""One test per controller block on a known input sequence, plus each block's bad-parameter errors."""

from __future__ import annotations

import math
import random

import pytest

from virtual_machine.controllers import (
    AnalogToPulse,
    CountToAnalog,
    DCMotor,
    Encoder,
    FrequencyDivider,
    HydraulicPulseGenerator,
    HydraulicSteppingMotor,
    Key,
    ParallelSummator,
    PhaseDiscriminator,
    PowerAmplifier,
    PulseToAnalog,
    ReferenceGenerator,
    SignDiscriminator,
    Summator,
    SynchronousMotor,
)

TWO_PI = 2.0 * math.pi


def run(block, pin: str, values, out: str = "out", dt: float = 1e-3) -> list:
    """Feed ``values`` into ``block.<pin>`` one tick each; return the ``block.<out>`` sequence."""
    result = []
    for v in values:
        setattr(block, pin, v)
        block.update(dt)
        result.append(getattr(block, out))
    return result


# --- pulses -------------------------------------------------------------------------------------


def test_reference_generator_exact_total_at_1ghz():
    gen = ReferenceGenerator(1e9)
    for _ in range(4000):
        gen.update(2.5e-4)
    assert abs(gen.position - 1_000_000_000) <= 1
    assert isinstance(gen.out, int)


def test_reference_generator_carries_fraction():
    gen = ReferenceGenerator(3.0)
    assert run(gen, "frequency", [3.0] * 4, dt=0.5) == [1, 2, 1, 2]  # 1.5 pulses per tick
    gen = ReferenceGenerator(1000.0)
    for n in range(1, 200):
        gen.update(2**-12)  # 0.244140625 pulses per tick, exact in binary
        assert gen.position == math.floor(1000.0 * n * 2**-12)


def test_frequency_divider_sequence_and_remainder():
    div = FrequencyDivider(7)
    assert run(div, "inp", [3, 3, 3, 3, 3]) == [0, 0, 1, 0, 1]
    assert (div.position, div.remainder) == (2, 1)
    # counting back down through the same positions undoes the output exactly
    assert run(div, "inp", [-3, -3, -3, -3, -3]) == [-1, 0, -1, 0, 0]
    assert (div.position, div.remainder) == (0, 0)
    # from zero downwards: a pulse at every multiple of k crossed (floor semantics)
    div.reset()
    assert run(div, "inp", [-3] * 5) == [-1, 0, -1, 0, -1]
    assert (div.position, div.remainder) == (-3, 6)


def test_frequency_divider_matches_floor_formula_and_large_counts():
    rng = random.Random(1)
    div = FrequencyDivider(13)
    s = 0
    for _ in range(2000):
        inp = rng.randint(-40, 40)
        div.inp = inp
        div.update(2.5e-4)
        assert div.out == (s + inp) // 13 - s // 13
        s += inp
    big = FrequencyDivider(7)
    big.inp = 1_000_000_000
    big.update(2.5e-4)
    assert (big.out, big.remainder) == (142_857_142, 6)


def test_frequency_divider_chain_6_7():
    rng = random.Random(2)
    d6, d7 = FrequencyDivider(6), FrequencyDivider(7)
    total = 0
    for _ in range(500):
        d6.inp = rng.randint(0, 1000)
        total += d6.inp
        d6.update(1e-3)
        d7.inp = d6.out
        d7.update(1e-3)
    assert d7.position == (total // 6) // 7


def test_frequency_divider_k_change_at_run_time():
    div = FrequencyDivider(10)
    run(div, "inp", [8])
    div.k = 5  # content 8 >= 5 overflows into the next output
    assert run(div, "inp", [0, 4]) == [1, 1]
    assert div.remainder == 2
    with pytest.raises(ValueError, match=r"k = 0 is invalid: must be an integer >= 1"):
        div.k = 0


@pytest.mark.parametrize("k", [0, -3, 2.5, True, "7"])
def test_frequency_divider_bad_k(k):
    with pytest.raises(ValueError, match=r"^k = .* must be an integer >= 1"):
        FrequencyDivider(k)


@pytest.mark.parametrize("f", [-1.0, math.nan, math.inf])
def test_reference_generator_bad_frequency(f):
    with pytest.raises(ValueError, match=r"^frequency = .*>= 0"):
        ReferenceGenerator(f)


def test_summator():
    s = Summator(-1)
    for a, b, out in [(5, 3, 2), (0, 4, -4), (-2, -2, 0)]:
        s.a, s.b = a, b
        s.update(1e-3)
        assert s.out == out
    s = Summator()
    s.a, s.b = 5, 3
    s.update(1e-3)
    assert s.out == 8
    with pytest.raises(ValueError, match=r"^sign = 0 is invalid: must be one of \(1, -1\)"):
        Summator(0)


# --- converters ---------------------------------------------------------------------------------


def test_pulse_to_analog_unfiltered():
    p2a = PulseToAnalog(gain=1e-3)
    assert run(p2a, "inp", [10, -5, 0]) == pytest.approx([10.0, -5.0, 0.0], rel=1e-15)  # 1e4, -5e3, 0 pulses/s


def test_pulse_to_analog_step_response():
    dt, tau, gain = 1e-3, 0.01, 2e-3
    p2a = PulseToAnalog(gain, tau)
    outs = run(p2a, "inp", [10] * 60, dt=dt)  # 1e4 pulses/s step
    for n, out in enumerate(outs, start=1):
        assert out == pytest.approx(gain * 1e4 * (1.0 - math.exp(-n * dt / tau)), rel=1e-12)


@pytest.mark.parametrize(("kwargs", "match"), [({"gain": 0.0}, r"^gain = 0.0"), ({"gain": 1.0, "tau": -1e-3}, r"^tau")])
def test_pulse_to_analog_bad_params(kwargs, match):
    with pytest.raises(ValueError, match=match):
        PulseToAnalog(**kwargs)


def test_count_to_analog():
    c2a = CountToAnalog(0.5)
    assert run(c2a, "inp", [3, -4, 0]) == [1.5, -2.0, 0.0]
    with pytest.raises(ValueError, match=r"^gain = nan"):
        CountToAnalog(math.nan)


def test_analog_to_pulse():
    dt = 2**-10
    vco = AnalogToPulse(256.0)  # 0.25 pulse per tick at inp = 1, exact in binary
    assert run(vco, "inp", [1.0] * 8, dt=dt) == [0, 0, 0, 1, 0, 0, 0, 1]
    vco.reset()
    # floor, like an encoder: the first reverse pulse comes at once, when the integral crosses 0
    assert run(vco, "inp", [-1.0] * 4, dt=dt) == [-1, 0, 0, 0]
    vco.reset()
    assert run(vco, "inp", [1.0, 1.0, -1.0, -1.0, -1.0], dt=dt) == [0, 0, 0, 0, -1]  # back below zero
    assert vco.position == -1
    vco.reset()
    run(vco, "inp", [4000.0], dt=dt)  # 1000 pulses in one tick
    assert vco.out == 1000
    with pytest.raises(ValueError, match=r"^gain = 0 "):
        AnalogToPulse(0)


# --- analog -------------------------------------------------------------------------------------


def test_parallel_summator():
    ps = ParallelSummator()
    ps.main, ps.add, ps.sub = 1.5, 0.25, 0.5
    ps.update(1e-3)
    assert ps.out == 1.25


def test_power_amplifier_saturation():
    amp = PowerAmplifier(10.0, 24.0)
    outs, flags = [], []
    for x in [1.0, 3.0, -3.0, -2.0]:
        amp.inp = x
        amp.update(1e-3)
        outs.append(amp.out)
        flags.append(amp.saturated)
    assert outs == [10.0, 24.0, -24.0, -20.0]
    assert flags == [False, True, True, False]
    with pytest.raises(ValueError, match=r"^limit = 0.0 is out of range: must be finite and > 0"):
        PowerAmplifier(10.0, 0.0)
    with pytest.raises(ValueError, match=r"^gain = inf"):
        PowerAmplifier(math.inf, 24.0)


def test_keys():
    lag, lead = Key(), Key()
    lag.inp = lead.inp = 2.5
    lag.closed = True
    lag.update(1e-3)
    lead.update(1e-3)
    assert (lag.out, lead.out) == (2.5, 0.0)
    lag.closed = False
    lag.update(1e-3)
    assert lag.out == 0.0


# --- encoder and discriminators -----------------------------------------------------------------


def test_encoder():
    enc = Encoder(1000)
    enc.angle = TWO_PI * 0.30001
    enc.update(1e-3)
    assert (enc.position, enc.count) == (1200, 1200)
    assert enc.counts_per_rev == 4000
    positions = run(enc, "angle", [TWO_PI * 0.25001, TWO_PI * -0.00001, TWO_PI * 1.00001], out="position")
    assert positions == [1000, -1, 4000]
    assert enc.count == 4001
    enc1 = Encoder(1000, quadrature=1, angle0=1.0)
    assert run(enc1, "angle", [1.0, 1.0 + TWO_PI * 0.5001, 1.0 - TWO_PI * 0.0001], out="count") == [0, 500, -501]


@pytest.mark.parametrize(
    ("args", "match"),
    [
        ((0,), r"^lines = 0 is invalid"),
        ((1000, 3), r"^quadrature = 3 .*one of \(1, 2, 4\)"),
        ((10, 4, math.nan), r"^angle0"),
    ],
)
def test_encoder_bad_params(args, match):
    with pytest.raises(ValueError, match=match):
        Encoder(*args)


def test_sign_discriminator_lag_negative_lead_positive():
    sd = SignDiscriminator()
    results = []
    for ref, fb in [(10, 7), (7, 10), (5, 5)]:  # lag, lead, equal
        sd.reference, sd.feedback = ref, fb
        sd.update(1e-3)
        results.append(sd.out)
    assert results == [-1, 1, 0]
    sd = SignDiscriminator(deadband=3)
    results = []
    for ref, fb in [(13, 10), (14, 10), (10, 14), (10, 13)]:
        sd.reference, sd.feedback = ref, fb
        sd.update(1e-3)
        results.append(sd.out)
    assert results == [0, -1, 1, 0]
    with pytest.raises(ValueError, match=r"^deadband = -1 is invalid: must be an integer >= 0"):
        SignDiscriminator(-1)


def test_phase_discriminator():
    pd = PhaseDiscriminator()
    results = []
    for ref, fb in [(10, 7), (7, 10), (5, 5), (-2_000_000_000, 3)]:
        pd.reference, pd.feedback = ref, fb
        pd.update(1e-3)
        results.append(pd.out)
    assert results == [3, 3, 0, 2_000_000_003]


# --- motors -------------------------------------------------------------------------------------


def dc(**kw) -> DCMotor:
    params = {"resistance": 2.0, "inductance": 0.0, "torque_constant": 0.5, "current_limit": 100.0}
    return DCMotor(**(params | kw))


def test_dc_motor_steady_state_without_inductance():
    m = dc()
    m.voltage, m.omega = 24.0, 10.0
    m.update(1e-3)
    assert (m.current, m.torque, m.at_limit) == (9.5, 4.75, False)  # (24 - 0.5*10)/2
    m = dc(back_emf=0.6)
    m.voltage, m.omega = 24.0, 10.0
    m.update(1e-3)
    assert m.current == pytest.approx(9.0, rel=1e-15)


def test_dc_motor_step_response():
    R, L, V, dt = 2.0, 0.01, 10.0, 1e-3
    m = dc(inductance=L)
    currents = run(m, "voltage", [V] * 50, out="current", dt=dt)
    for n, i in enumerate(currents, start=1):
        assert i == pytest.approx(V / R * (1.0 - math.exp(-n * dt * R / L)), rel=1e-12)


def test_dc_motor_current_limit():
    m = dc(resistance=1.0, current_limit=10.0)
    assert run(m, "voltage", [100.0, -100.0, 5.0], out="current") == [10.0, -10.0, 5.0]
    assert not m.at_limit
    m.voltage = -100.0
    m.update(1e-3)
    assert (m.torque, m.at_limit) == (-5.0, True)


@pytest.mark.parametrize(
    ("kw", "name"),
    [
        ({"resistance": 0.0}, "resistance"),
        ({"inductance": -1e-3}, "inductance"),
        ({"torque_constant": -0.5}, "torque_constant"),
        ({"current_limit": 0.0}, "current_limit"),
        ({"back_emf": 0.0}, "back_emf"),
    ],
)
def test_dc_motor_bad_params(kw, name):
    with pytest.raises(ValueError, match=rf"^{name} = .* must be finite and "):
        dc(**kw)


def test_synchronous_motor_current_loop_and_limit():
    kt, bw, dt = 1.2, 500.0, 2.5e-4
    m = SynchronousMotor(torque_constant=kt, current_limit=5.0, bandwidth=bw)
    currents = run(m, "current_command", [3.0] * 20, out="current", dt=dt)
    for n, i in enumerate(currents, start=1):
        assert i == pytest.approx(3.0 * (1.0 - math.exp(-n * dt * TWO_PI * bw)), rel=1e-12)
    assert m.torque == pytest.approx(kt * currents[-1], rel=1e-15)
    m.reset()
    run(m, "current_command", [100.0] * 200, out="current", dt=dt)
    assert m.current == pytest.approx(5.0, rel=1e-12)
    assert m.at_limit


@pytest.mark.parametrize("name", ["torque_constant", "current_limit", "bandwidth"])
def test_synchronous_motor_bad_params(name):
    params = {"torque_constant": 1.0, "current_limit": 5.0, "bandwidth": 500.0} | {name: 0.0}
    with pytest.raises(ValueError, match=rf"^{name} = 0.0 is out of range: must be finite and > 0"):
        SynchronousMotor(**params)


# --- hydraulic ----------------------------------------------------------------------------------


def test_hydraulic_pulse_generator():
    ggi = HydraulicPulseGenerator(24)
    revs = [0.1, 0.5, 1.01, 0.99, -0.01]
    assert run(ggi, "angle", [TWO_PI * r for r in revs]) == [2, 10, 12, -1, -24]
    assert ggi.position == -1
    with pytest.raises(ValueError, match=r"^windows = 0 is invalid"):
        HydraulicPulseGenerator(0)


def shd(**kw) -> HydraulicSteppingMotor:
    params = {"steps_per_rev": 200, "stiffness": 1000.0, "damping": 0.0, "leakage": 0.0, "torque_limit": 1e6}
    return HydraulicSteppingMotor(**(params | kw))


def test_hydraulic_shaft_ratio():
    ggi, gshd = HydraulicPulseGenerator(24), shd(steps_per_rev=48)
    for k in range(1, 101):  # one master revolution in 100 ticks
        ggi.angle = TWO_PI * k / 100 + 1e-9
        ggi.update(1e-3)
        gshd.pulses = ggi.out
        gshd.update(1e-3)
    assert gshd.steps == 24
    assert gshd.commanded == pytest.approx(math.pi, rel=1e-15)  # ratio 24/48


def test_hydraulic_stepping_motor_zero_load_stiffness_and_damping():
    m = shd()
    step = TWO_PI / 200
    m.pulses = 5
    m.update(1e-3)
    assert m.commanded == pytest.approx(5 * step, rel=1e-15)
    assert m.torque == pytest.approx(1000.0 * 5 * step, rel=1e-15)
    m.pulses, m.angle = 0, 5 * step  # shaft caught up: no torque
    m.update(1e-3)
    assert m.torque == pytest.approx(0.0, abs=1e-12)
    d = shd(damping=2.0)
    d.pulses = 1
    d.update(1e-3)
    assert d.torque == pytest.approx(1000.0 * step + 2.0 * step / 1e-3, rel=1e-14)
    d.pulses, d.omega = 0, 0.5
    d.update(1e-3)
    assert d.torque == pytest.approx(1000.0 * step - 2.0 * 0.5, rel=1e-14)


def test_hydraulic_stepping_motor_torque_clamp():
    m = shd(torque_limit=10.0)
    assert run(m, "pulses", [100, -200, 100], out="torque") == [10.0, -10.0, 0.0]
    assert not m.at_limit
    m.pulses = -1
    m.update(1e-3)
    assert m.at_limit


def test_hydraulic_stepping_motor_leakage_creep():
    T, leak, dt, n = 10.0, 0.01, 1e-3, 1000
    m = shd(torque_limit=T, leakage=leak)
    m.angle = -100.0  # held far behind: the torque stays at the limit
    for _ in range(n):
        m.update(dt)
        assert m.torque == T
    # the creep uses the previous tick's torque, which is 0 before the first update
    assert m.commanded == pytest.approx(-leak * T * (n - 1) * dt, abs=1e-12)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"steps_per_rev": 0}, r"^steps_per_rev = 0 is invalid: must be an integer >= 1"),
        ({"stiffness": 0.0}, r"^stiffness = 0.0 .*> 0"),
        ({"damping": -1.0}, r"^damping = -1.0 .*>= 0"),
        ({"leakage": -1.0}, r"^leakage = -1.0 .*>= 0"),
        ({"torque_limit": math.inf}, r"^torque_limit = inf"),
    ],
)
def test_hydraulic_stepping_motor_bad_params(kw, match):
    with pytest.raises(ValueError, match=match):
        shd(**kw)


# --- common contract ----------------------------------------------------------------------------

BLOCKS = [
    (lambda: ReferenceGenerator(1234.5), "frequency", 1234.5),
    (lambda: Summator(-1), "a", 3),
    (lambda: PulseToAnalog(1e-3, 0.01), "inp", 7),
    (lambda: CountToAnalog(0.1), "inp", 7),
    (lambda: AnalogToPulse(1e4), "inp", 0.37),
    (ParallelSummator, "main", 1.0),
    (lambda: PowerAmplifier(10.0, 1.0), "inp", 0.5),
    (Key, "closed", True),
    (lambda: Encoder(1000), "angle", 0.123),
    (SignDiscriminator, "reference", 5),
    (PhaseDiscriminator, "reference", 5),
    (lambda: dc(inductance=0.01), "voltage", 12.0),
    (lambda: SynchronousMotor(torque_constant=1.0, current_limit=5.0, bandwidth=500.0), "current_command", 2.0),
    (lambda: HydraulicPulseGenerator(24, 0.5), "angle", 3.0),
    (lambda: shd(leakage=0.01, damping=1.0), "pulses", 3),
]


@pytest.mark.parametrize(("make", "pin", "value"), BLOCKS)
def test_reset_restores_constructed_state_and_slots(make, pin, value):
    block, fresh = make(), make()
    assert not hasattr(block, "__dict__")
    for _ in range(5):
        setattr(block, pin, value)
        block.update(1e-3)
    assert block != fresh
    block.reset()
    assert block == fresh


def test_frequency_divider_reset_and_slots():
    div = FrequencyDivider(7)
    assert not hasattr(div, "__dict__")
    run(div, "inp", [3, 5])
    div.reset()
    assert (div.inp, div.out, div.position, div.remainder, div.k) == (0, 0, 0, 0, 7)


# ---- speed regulator (power amplifier's speed loop) -------------------------------------------------
def test_speed_regulator_pi_and_anti_windup() -> None:
    from virtual_machine.controllers import SpeedRegulator

    r = SpeedRegulator(kp=2.0, ki=100.0, limit=10.0)
    r.speed_command, r.tacho = 1.0, 0.0
    r.update(0.01)
    assert r.out == pytest.approx(2.0 * 1.0 + 100.0 * 0.01)  # kp e + ki e dt
    r.speed_command = 100.0  # far beyond the limit: clamps and stops integrating
    for _ in range(50):
        r.update(0.01)
    assert r.out == 10.0 and r.saturated
    r.speed_command = 0.0  # the integral did not wind up: the output leaves the limit at once
    r.update(0.01)
    assert r.out == pytest.approx(100.0 * 0.01)
    with pytest.raises(ValueError, match="limit"):
        SpeedRegulator(kp=1.0, ki=0.0, limit=0.0)


def test_rate_multiplier_is_exact_on_average() -> None:
    from virtual_machine.controllers import RateMultiplier

    m = RateMultiplier(3, 7)  # 3/7 output pulse per input pulse
    outs = [(m.__setattr__("inp", x), m.update(1e-3), m.out)[2] for x in (5, 5, 5, -15)]
    assert outs == [2, 2, 2, -6]  # 15, 30, 45 counted -> floor(45/7) = 6; back to zero
    assert m.position == 0 and m.remainder == 0
    m.inp = 7
    m.update(1e-3)
    assert m.out == 3 and m.fine_position == 3.0
    with pytest.raises(ValueError, match=r"^n = 0"):
        RateMultiplier(0, 3)


def test_induction_motor_slip_line_and_breakdown() -> None:
    from virtual_machine.controllers import InductionMotor

    m = InductionMotor(sync_speed=157.0, rated_torque=70.0, rated_slip=0.03)
    m.scale, m.omega = 1.0, 157.0 * (1 - 0.03)
    m.update(1e-3)
    assert m.torque == pytest.approx(70.0)  # rated slip -> rated torque
    m.scale = 0.5  # half frequency: the same slip speed gives the same torque
    m.omega = 157.0 * 0.5 - 157.0 * 0.03
    m.update(1e-3)
    assert m.torque == pytest.approx(70.0)
    m.omega = 0.0
    m.update(1e-3)
    assert m.torque == 175.0 and m.at_limit
    with pytest.raises(ValueError, match="rated_slip"):
        InductionMotor(sync_speed=1.0, rated_torque=1.0, rated_slip=1.5)
