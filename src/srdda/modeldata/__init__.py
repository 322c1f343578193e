"""The model's data: the records that the builder, the terms, the state and the step all name.

- :mod:`.materials`: ``ModelError``, ``Material``, ``JointMaterial``, ``JointTable``, ``elasticity_matrix``;
- :mod:`.constraints`: the specs of hinges, springs, driven points and bolts and their ``ConstraintArrays``;
- :mod:`.water`: the ``WaterTable`` and its ``TensionCrack``\\ s;
- :mod:`.stages`: the ``StagePlan``, a stage resolved against its model;
- :mod:`.arrays`: ``ModelArrays`` (the model as flat arrays for the time loop) and its ``AttachedPoints``.

These modules import no term, no builder and no package whose ``__init__`` does, so that everything above
them (the terms, the state, the step, the stages, the builder :class:`srdda.model.Model`) names them without an
import circle (docs/architecture.md, *Import circles*). Their public homes stay where they were:
:mod:`srdda.model`, :mod:`srdda.constraints`, :mod:`srdda.constraints.data`, :mod:`srdda.constraints.water` and
:mod:`srdda.stages` re-export them.
"""
