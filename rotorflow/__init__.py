"""rotorflow: rotors of rotary positive-displacement machines, from profile to CFD check."""

__version__ = "0.1.0"
