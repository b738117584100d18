"""Dataset contracts of parameter spaces and designs (shared by every stage that produces or consumes them)."""

from spflow.core.schema import DatasetSchema, Variable

#: A box of uncertain forward-model parameters (dim ``param``; coordinate = UTCHEM parameter names).
SPACE = DatasetSchema(
    dims=("param",),
    variables={
        "lower": Variable(("param",), units=None),
        "upper": Variable(("param",), units=None),
        "default": Variable(("param",), units=None),
        "unit": Variable(("param",), kind="U"),
    },
    doc="uncertain parameters with uniform bounds",
)

#: Sample points in a parameter space (dims ``sample``, ``param``).
DESIGN = DatasetSchema(
    dims=("sample", "param"),
    variables={"values": Variable(("sample", "param"), units=None)},
    doc="design points",
)
