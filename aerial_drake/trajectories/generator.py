"""The reference trajectory as a Drake system: :class:`ReferenceGenerator`."""

from __future__ import annotations

import copy

from pydrake.systems.framework import BasicVector, Context, Diagram, DiagramBuilder, LeafSystem
from pydrake.systems.primitives import Demultiplexer

from aerial_drake.trajectories.base import ReferenceSource
from aerial_drake.trajectories.kinds import reference_of
from aerial_drake.trajectories.params import TrajectoryParams
from aerial_drake.trajectories.reference import (
    COM_REFERENCE_SIZE,
    HEADING_REFERENCE_SIZE,
    task_reference_size,
)

__all__ = ["ReferenceGenerator"]


class _PackedReference(LeafSystem):
    """The concatenation [com, task, heading] at the context time: one output, so one
    Python call per time; :class:`ReferenceGenerator` splits it in C++."""

    def __init__(self, source: ReferenceSource):
        super().__init__()
        self._fill = source.fill
        self.DeclareVectorOutputPort("references", source.size, self._calc,
                                     prerequisites_of_calc={self.time_ticket()})

    def _calc(self, context: Context, output: BasicVector) -> None:
        self._fill(context.get_time(), output.get_mutable_value())


class ReferenceGenerator(Diagram):
    """The reference trajectory of any kind (:mod:`aerial_drake.trajectories.kinds`; the
    paper's (28)-(33) by default) as a Drake source: no state, no inputs.

    Output ports (functions of the context's time only; layouts in
    :mod:`aerial_drake.trajectories.reference`): ``com_reference`` (15), ``task_reference``
    (24 + 3 n_j: 27 for the paper's task), ``heading_reference`` (9).

    ``reference``: the run's :class:`~aerial_drake.trajectories.base.ReferenceSource` (built
    once by :func:`~aerial_drake.trajectories.kinds.reference_of` and shared with the run's
    checks and logs, :attr:`source`), or the ``trajectory:`` section's parameters to build it
    from; ``joint_defaults``, with parameters: the desired angles of the task's joint
    components when their ``joint_targets`` is empty (the robot's nominal posture there).

    A small Diagram: the three are computed together, once per time, by one compiled call in
    a LeafSystem with a single output, and Drake's Demultiplexer splits them. The controller
    reads all three at every sample: one Python call instead of one per port (and a cache
    entry) saves about three quarters of the generator's cost in the closed loop.

    Double only (no AutoDiffXd / Expression conversion): its outputs depend on time alone, so
    linearise a diagram about a hover point with a ConstantVectorSource in its place.
    """

    def __init__(self, reference: TrajectoryParams | ReferenceSource, joint_defaults=None):
        super().__init__()
        if isinstance(reference, ReferenceSource):
            source, self._params = reference, None
        else:
            source, self._params = reference_of(reference, joint_defaults), copy.deepcopy(
                reference)
        #: The reference this system outputs (the same object, not a copy).
        self.source = source
        self.n_joints = source.n_joints
        builder = DiagramBuilder()
        packed = builder.AddSystem(_PackedReference(source))
        packed.set_name("packed_reference")
        split = builder.AddSystem(Demultiplexer(
            [COM_REFERENCE_SIZE, task_reference_size(self.n_joints), HEADING_REFERENCE_SIZE]))
        split.set_name("split_reference")
        builder.Connect(packed.get_output_port(), split.get_input_port())
        names = ("com_reference", "task_reference", "heading_reference")
        for i, name in enumerate(names):
            builder.ExportOutput(split.get_output_port(i), name)
        builder.BuildInto(self)
        self._com_port, self._task_port, self._heading_port = map(self.GetOutputPort, names)

    def params(self) -> TrajectoryParams | None:
        """A copy of the parameters this system was built with (None if built from a
        ReferenceSource)."""
        return copy.deepcopy(self._params)

    def get_com_reference_output_port(self):
        return self._com_port

    def get_task_reference_output_port(self):
        return self._task_port

    def get_heading_reference_output_port(self):
        return self._heading_port
