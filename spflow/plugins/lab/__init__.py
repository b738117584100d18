"""Prior calibration from the support experiments of thesis chapter 2 (Fig. 2.1, section 2.12).

Each lab test (polymer rheology, single-phase polymer coreflood, adsorption, tracer, phase behaviour, IFT,
microemulsion viscosity, capillary desaturation) is read from a small CSV lab table (:mod:`.lab_table`), fitted to its
own sub-model of the forward simulator by weighted least squares (:mod:`.fit_result`), and returned as a FIT dataset
of estimates, standard errors and covariance under the forward model's UTCHEM parameter names.
"""
