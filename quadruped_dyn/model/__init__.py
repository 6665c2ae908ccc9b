"""The robot as data: legs, the URDF loader and its rules, the state conventions, stance sets,
the paper's DH robot."""
