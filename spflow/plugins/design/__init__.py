"""Parameter spaces and experimental designs (Latin hypercube) over forward-model parameters."""
