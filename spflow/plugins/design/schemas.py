"""Dataset contracts of parameter spaces and designs (shared by every stage that produces or consumes them)."""

from spflow.core.schema import DatasetSchema, Variable
from spflow.plugins.design.parameter_map import NAMES_VAR, SCALE_VAR
from spflow.plugins.surrogates.input_marginals import MARGINAL_SCHEMA

#: The parameter map of a space or design (:mod:`spflow.plugins.design.parameter_map`): optional, absent = each
#: column is the UTCHEM name it sets, on a linear scale.
MAP_VARIABLES = {
    NAMES_VAR: Variable(("param",), kind="UO", required=False,
                        long_name="forward-model (UTCHEM) parameters each column sets",
                             doc="forward-model (UTCHEM) parameters each column sets, separated by spaces"),
    SCALE_VAR: Variable(("param",), kind="UO", required=False,
                        long_name="linear: the column is the value; log: the column is log10 of the value",
                      doc="linear: the column is the value; log: the column is log10 of the value"),
}

#: A box of uncertain forward-model parameters (dim ``param``; coordinate = column labels: UTCHEM names or labels of
#: groups, with the parameter map). The bounds have units per element, ``unit`` (:mod:`spflow.core.cf_metadata`).
SPACE = DatasetSchema(
    dims=("param",),
    variables={
        "lower": Variable(("param",), units_variable="unit", long_name="lower end of the range"),
        "upper": Variable(("param",), units_variable="unit", long_name="upper end of the range"),
        "default": Variable(("param",), units_variable="unit", long_name="default value"),
        "unit": Variable(("param",), kind="U", long_name="UDUNITS unit of each column"),
    } | MAP_VARIABLES,
    doc="uncertain parameters with uniform bounds",
)

#: Sample points in a parameter space (dims ``sample``, ``param``). With ``unit`` (a design drawn from a space),
#: ``values`` has units per element; a design without it (hand-made, or from draws) carries no units. A design drawn
#: from a space's marginals (``lhs_design``) records them (``distribution`` / ``distribution_parameters``).
DESIGN = DatasetSchema(
    dims=("sample", "param"),
    variables={"values": Variable(("sample", "param"), units=None, long_name="design points"),
               "unit": Variable(("param",), kind="U", required=False, long_name="UDUNITS unit of each column")}
    | MAP_VARIABLES | MARGINAL_SCHEMA,
    doc="design points",
)

#: A design a stage draws from a space or a calibration (``lhs_design``, ``pareto_design``): :data:`DESIGN` with
#: ``unit`` required, so ``values`` has units per element. Stages that take a design accept :data:`DESIGN` (a
#: design a user gives, ``Pipeline.add_data`` or ``load_netcdf``, may carry no units).
DESIGN_WITH_UNITS = DatasetSchema(
    dims=DESIGN.dims,
    variables=DESIGN.variables | {
        "values": Variable(("sample", "param"), units_variable="unit", long_name="design points"),
        "unit": Variable(("param",), kind="U", long_name="UDUNITS unit of each column")},
    doc="design points with the units of their columns",
)
