"""The scenario core's old home, kept so that ``from rigidbench.scenario import ...`` goes on working.

Split by concern (issue 34): what a scenario author writes is `rigidbench.contract` (Param, Case, Check, Domain,
Derived, the `Scenario` hooks); what is done with a scenario (resolve, build, prepare, run, score) is
`rigidbench.harness`. New code imports from those.
"""

from rigidbench.contract import (  # noqa: F401
    BUILD_LOCK,
    Case,
    CaseValue,
    Check,
    Derived,
    Domain,
    OutsideDomain,
    Params,
    Scenario,
    _defaults,
    _model_xml,
)
from rigidbench.harness import PER_CHECK, UNRESOLVED_FRACTION, CaseRun, Outcome, Prepared  # noqa: F401
from rigidbench.params import Bound, Param, Range, Value  # noqa: F401
from rigidbench.trajectory import Trajectory  # noqa: F401
