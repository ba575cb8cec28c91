"""``paper_force``: the paper's law with a force task along a contact normal, an admittance
outer loop on the end-effector reference fed by a measured contact force (docs/contact.md)."""
