"""spflow's framework core: stages, schemas, params, pipelines, hashing, the store, plugins and the executor."""
