"""The internal-gear (pin-generated, gerotor-type) family: seeds 000 and 001."""

from .family import FAMILY
from .pair import PinGerotor, sigma_limit

__all__ = ["FAMILY", "PinGerotor", "sigma_limit"]
