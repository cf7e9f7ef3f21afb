"""The ship: sea states, spectra, RAOs, the paper mode and the MMG manoeuvring model (truth)."""


