"""What is flown: building the ``MultibodyPlant`` of the helicopter and the arm
(:mod:`.models`) and where the model files are, in a checkout or an install (:mod:`.resources`).
"""
