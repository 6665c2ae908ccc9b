"""The paper's experiment: the gait plan, inverse kinematics along it, the reduced forward
dynamics, the rigid-contact physics check, and the comparison with the plan and its files."""
