"""Other libraries as references, behind one interface in the project's conventions: Pinocchio
(the ground truth), MuJoCo and iDynTree. Nothing in ``dynamics`` imports them."""
