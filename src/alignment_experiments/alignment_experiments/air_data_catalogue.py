"""The air-data experiments (seed 004): Monte Carlo runs of the air-data estimators on a
scenario, cells = estimator form x algorithm, with the paper's claims to put ours beside."""
from __future__ import annotations

from dataclasses import dataclass, replace

QUANTITIES = ('mach', 'alpha_rad', 'beta_rad')
SHOWN = {'mach': ('Mach', 1.0, ''), 'alpha_rad': ('alpha', 57.29577951308232, ' deg'),
         'beta_rad': ('beta', 57.29577951308232, ' deg')}          # name, scale to the shown unit, unit


@dataclass(frozen=True)
class AirDataCell:
    label: str
    form: str
    algorithm: str
    overrides: tuple[tuple[str, object], ...] = ()


@dataclass(frozen=True)
class PaperClaim:
    """Seed 004's published bound on a quantity's error (|error| < bound) and, per quantity, the
    CKF's cut of the maximum error against the EKF (fraction; None where not given)."""
    quantity: str
    bound: float
    ckf_cut_of_max: float | None = None


@dataclass(frozen=True)
class AirDataExperiment:
    name: str
    title: str
    description: str
    scenario: str
    cells: tuple[AirDataCell, ...]
    seeds: int = 100
    base: tuple[tuple[str, object], ...] = ()
    settle_s: float = 10.0                     # errors counted from here (the first frames initialise)
    window: tuple[float, float] = (0.0, 1e9)   # the RMS window (seed 004: the cruise)
    check_every_s: float = 50.0                # NEES across runs at these instants
    wind_after_s: float | None = None          # wind scored from here (after the first turn)
    fault_at_s: float | None = None            # a cell with `fads.faults` fails a port here
    claims: tuple[PaperClaim, ...] = ()
    quick_base: tuple[tuple[str, object], ...] = ()
    quick_cells: tuple[str, ...] = ()
    notes: str = ''
    sweep: str = ''

    def quick(self, seeds: int = 2) -> AirDataExperiment:
        cells = tuple(c for c in self.cells if c.label in self.quick_cells) or self.cells
        return replace(self, base=self.base + self.quick_base, cells=cells, seeds=seeds)


def _cells() -> tuple[AirDataCell, ...]:
    return tuple(AirDataCell(f'{form} {alg}', form, alg)
                 for form in ('paper', 'tight') for alg in ('ekf', 'ukf', 'ckf'))


SEED004_TABLES = AirDataExperiment(
    name='seed004_tables',
    title="Seed 004: FADS + IMU air data, EKF / UKF / CKF, the paper's form and the tightly coupled one",
    description=("Seed 004's flight (1 -> 20 km, Mach 0.1 -> 7 -> 0.1, alpha to +-50 deg, beta to +-20 deg; "
                 "FADS at 1 Hz, 20 Pa Gauss-Markov port noise; config/scenarios/seed004.yaml). The paper's "
                 "3-state filter (FADS solve as the measurement) and the tightly coupled one (port pressures as "
                 "measurements), each as EKF, UKF and CKF, on the same random draws. Errors after the first "
                 "10 s; RMS over the Mach 7 cruise (220-700 s)."),
    scenario='seed004',
    cells=_cells(),
    seeds=100,
    window=(220.0, 700.0),
    claims=(PaperClaim('mach', 0.01), PaperClaim('alpha_rad', 0.1 / 57.29577951308232, 0.39),
            PaperClaim('beta_rad', 0.1 / 57.29577951308232, 0.47)),
    quick_base=(('duration_s', 300.0),),
    # the quick version (the suite's freshness check) runs the tight form only: the paper form's
    # gate sits near its NIS often enough that another CPU's last bits flip one update
    quick_cells=('tight ckf',),
    notes=("The paper's form gives the same numbers as EKF, UKF and CKF: given the INS attitude its "
           "process and measurement are linear in the state, so the CKF's 39 % / 47 % cut of the maximum "
           "errors cannot come from this model (our cut: 0 %). It is inconsistent (NEES far above its "
           "bounds) because it treats the ports as white and instantaneous: their noise is correlated and "
           "they lag, so its estimate trails the alpha sweeps. The tightly coupled form models both and is "
           "a little conservative; over the Mach 7 cruise it meets 0.02 deg and Mach 0.003 with a wide "
           "margin, and its Mach error stays inside the paper's 0.01 over the whole profile. Its worst "
           "alpha and beta errors come in the first seconds at Mach 0.1 near the ground, where one frame's "
           "Cramer-Rao bound is 1.5 deg and the filter has had a handful of correlated frames: there they "
           "reach about 2.5x (alpha) and 1.9x (beta) that bound, beyond the 1.5x goal. The EKF and CKF "
           "of the tight form differ by a few per cent only: the port model is smooth over one sigma."),
)

AIR_DATA_GOAL = AirDataExperiment(
    name='air_data_goal',
    title='Air-data goal: the tightly coupled CKF on a carrier flight, wind, NEES and a blocked port',
    description=("config/scenarios/carrier_flight.yaml: the catapult alignment, then a climb to 10 km at Mach "
                 "0.8, a 30 deg bank turn (580-700 s) and a climb to 15 km at Mach 0.9, in a 12 m/s wind with "
                 "moderate Dryden turbulence on an ISA + 8 K day; FADS at 10 Hz; the air-data filter reads the "
                 "transfer-aligned INS (the alignment filter's solution). Cells: nominal, and port 1 (bottom) "
                 "blocked at 550 s (mid-cruise at 10 km). Angles RMS over 200 s to the end; wind after the "
                 "first turn (from 700 s). Goals: wind <= 0.5 m/s with an honest sigma, alpha and beta <= 0.1 "
                 "deg, the blocked port excluded within 2 s and the errors afterwards within 2x the nominal."),
    scenario='carrier_flight',
    cells=(AirDataCell('tight ckf', 'tight', 'ckf'),
           AirDataCell('tight ckf, port 1 blocked at 550 s', 'tight', 'ckf',
                       (('fads.faults', 'blocked port=1 at_s=550'),))),
    seeds=20,
    settle_s=200.0,
    window=(200.0, 1000.0),
    wind_after_s=700.0,
    fault_at_s=550.0,
    quick_base=(('duration_s', 620.0),),
    notes=("Nominal: the wind after the first turn meets 0.5 m/s (east at the limit) with an honest "
           "sigma (NEES inside its bounds), Mach to 0.001. Alpha and beta come out at 0.104 deg RMS, just "
           "above the 0.1 goal: the limit is the pneumatic lag in moderate turbulence, the gusts inside each "
           "port's lag window that no state can know (modelled as measurement noise, which keeps the "
           "NEES honest; without a lag the same filter gives half the error). The blocked port is found "
           "in every run but after 18 s (median), not 2 s: a frozen port is only wrong as the flow "
           "changes, the bottom and top ports of a meridian explain each other's fault until one is "
           "clearly the culprit, and the gate refuses frames meanwhile; over the run the errors of that "
           "cell are 2.2x (alpha) and 2.3x (wind) the nominal ones, above the 2x goal."),
)

AIR_DATA_EXPERIMENTS = {e.name: e for e in (SEED004_TABLES, AIR_DATA_GOAL)}
