"""The physical world of the LED link: constants, optics, models, MuJoCo scene, simulation."""

from .config import LinkConstants, ReceiverResponse
from .paper_model import LEDLinkModel

__all__ = ["LinkConstants", "ReceiverResponse", "LEDLinkModel"]
