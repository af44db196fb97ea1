"""Zhai 2007's central contributions and the claims that decide them (the verdict word is
computed from the committed reports: :mod:`fusetrack.evaluation.verdict`)."""

from ...evaluation import Contribution, PaperVerdict, Reading, refs

#: The unprinted model details swept in E2, E4 and E13 (``e2_readings``, ``e4_readings``,
#: ``e13_readings``): claim ids ``R_<reading>_<claim>``.
_T = ("T=0.5", "T=0.3", "T=0.25", "T=0.1")
_Q_SIGMA = ("Q=0.005", "Q=0.5", "sigma_n^2=0.001", "sigma_n^2=0.0001")


_NARROW = "narrowDOA_wideprior"
_NAMES = {_NARROW: "narrow DOA noise, wide prior"}


def _readings(experiment: str, names: tuple[str, ...], claim: str) -> tuple[Reading, ...]:
    """One reading per swept detail, decided by that reading's version of ``claim``."""
    return tuple(
        Reading(_NAMES.get(name, name), refs(experiment, f"R_{name}_{claim}")) for name in names
    )


VERDICT = PaperVerdict(
    "Zhai 2007",
    "zhai2007",
    (
        Contribution(
            "Ch. 3: the PF-SP-PEKF proposal beats the bootstrap filter (with ten times the "
            "particles) and the EKF on the scalar benchmark (Tables 2-3)",
            refs("zhai2007-scalar", "C1_order"),
            readings=tuple(
                Reading(name, refs("zhai2007-scalar", f"C1_order_variant_{name}"))
                for name in ("z=x^2", "z=x^2/20", "sigma_v^2=100")
            ),
            best_possible=refs(
                "zhai2007-scalar",
                *(
                    f"BP_{test}_{method}"
                    for test, methods in (
                        ("possible", ("EKF", "BS200", "BS1000", "BS2000", "PF-SP-PEKF")),
                        ("converged", ("BS200", "BS1000", "BS2000")),
                    )
                    for method in methods
                ),
            ),
        ),
        Contribution(
            "Ch. 3: PF-SP-PEKF beats the bootstrap and the EKF in bearings-only tracking "
            "(Figs 10-12)",
            refs("zhai2007-bearings", "C4_order_E2", "C4_order_E3"),
            readings=_readings("zhai2007-bearings", ("T=0.25", *_Q_SIGMA, _NARROW), "C4_order"),
        ),
        Contribution(
            "Ch. 4: the Galerkin-projection PF with 200 particles beats the bootstrap with 2000 "
            "(Table 9)",
            refs("zhai2007-galerkin", "C12_beats_bs2000"),
            readings=_readings("zhai2007-galerkin", (*_T, *_Q_SIGMA, _NARROW), "C12"),
            best_possible=refs(
                "zhai2007-galerkin",
                *(f"BP_possible_bootstrap_{n}" for n in (200, 500, 1000, 2000)),
                "BP_possible_Galerkin_PF_200",
            ),
        ),
        Contribution(
            "Ch. 3: CPF-SP tracks on the acoustic sensor network with under a quarter of the "
            "centralised bootstrap's error (Table 5)",
            refs("zhai2007-sensor-network", "C5_cpfsp_vs_bootstrap"),
            readings=_readings("zhai2007-sensor-network", _Q_SIGMA, "C5"),
            best_possible=refs(
                "zhai2007-sensor-network",
                "BP_possible_CPF-SP",
                "BP_possible_bootstrap",
                "BP_converged_bootstrap",
            ),
        ),
        Contribution(
            "Ch. 6: MCMC moves (random-walk Metropolis) reduce the particle filter's error at "
            "every particle count (Table 15)",
            refs("zhai2007-mcmc", "C15_PF-RWM_beats_PF"),
            best_possible=refs("zhai2007-mcmc", "BP_possible_table15"),
        ),
    ),
)
