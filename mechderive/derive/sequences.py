"""The twelve Euler sequences for ``derive``: re-exported from :mod:`mechderive.kinematics.sequences`.

>>> scipy_sequence("XYZ", frame="space")
'xyz'
"""

from ..kinematics.sequences import (FRAMES, PROPER, SEQUENCES, TAIT_BRYAN, SequenceKinematics,  # noqa: F401
                                    angular_velocity_sequence, check_sequence, rotation_sequence, scipy_sequence,
                                    sequence_model)

__all__ = ["PROPER", "TAIT_BRYAN", "SEQUENCES", "FRAMES", "check_sequence", "scipy_sequence",
           "SequenceKinematics", "sequence_model", "rotation_sequence", "angular_velocity_sequence"]
