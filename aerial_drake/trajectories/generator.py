"""The reference trajectory as a Drake system: :class:`ReferenceGenerator`."""

import copy

import numpy as np
from pydrake.systems.framework import BasicVector, Context, Diagram, DiagramBuilder, LeafSystem
from pydrake.systems.primitives import Demultiplexer

from aerial_drake.trajectories.paper import TrajectoryParams, _Constants, _fill_reference
from aerial_drake.trajectories.reference import (
    _TOTAL_SIZE,
    COM_REFERENCE_SIZE,
    HEADING_REFERENCE_SIZE,
    TASK_REFERENCE_SIZE,
)

__all__ = ["ReferenceGenerator"]


class _PackedReference(LeafSystem):
    """The concatenation [com, task, heading] (51) at the context time: one output, so one
    Python call per time; :class:`ReferenceGenerator` splits it in C++."""

    def __init__(self, constants: np.ndarray):
        super().__init__()
        self._constants = constants
        self.DeclareVectorOutputPort("references", _TOTAL_SIZE, self._calc,
                                     prerequisites_of_calc={self.time_ticket()})

    def _calc(self, context: Context, output: BasicVector) -> None:
        _fill_reference(self._constants, context.get_time(), output.get_mutable_value())


class ReferenceGenerator(Diagram):
    """The reference trajectory (28)-(33) as a Drake source: no state, no inputs.

    Output ports (functions of the context's time only; layouts in the module docstring):
    ``com_reference`` (15), ``task_reference`` (27), ``heading_reference`` (9).

    A small Diagram: the three are computed together, once per time, by one compiled call in
    a LeafSystem with a single output, and Drake's Demultiplexer splits them. The controller
    reads all three at every sample: one Python call instead of one per port (and a cache
    entry) saves about three quarters of the generator's cost in the closed loop.

    Double only (no AutoDiffXd / Expression conversion): its outputs depend on time alone, so
    linearise a diagram about a hover point with a ConstantVectorSource in its place.
    """

    def __init__(self, params: TrajectoryParams):
        super().__init__()
        params.validate()
        self._params = copy.deepcopy(params)
        builder = DiagramBuilder()
        packed = builder.AddSystem(_PackedReference(_Constants.from_params(params).as_array()))
        packed.set_name("packed_reference")
        split = builder.AddSystem(
            Demultiplexer([COM_REFERENCE_SIZE, TASK_REFERENCE_SIZE, HEADING_REFERENCE_SIZE]))
        split.set_name("split_reference")
        builder.Connect(packed.get_output_port(), split.get_input_port())
        names = ("com_reference", "task_reference", "heading_reference")
        for i, name in enumerate(names):
            builder.ExportOutput(split.get_output_port(i), name)
        builder.BuildInto(self)
        self._com_port, self._task_port, self._heading_port = map(self.GetOutputPort, names)

    def params(self) -> TrajectoryParams:
        """A copy of the parameters this system was built with."""
        return copy.deepcopy(self._params)

    def get_com_reference_output_port(self):
        return self._com_port

    def get_task_reference_output_port(self):
        return self._task_port

    def get_heading_reference_output_port(self):
        return self._heading_port
