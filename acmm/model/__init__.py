"""The plant: rigid-body dynamics and kinematics (eqs 3.1–3.9), the torque-equilibrium attitude
(eqs 4.1–4.3), the 24-state linearization (eqs 4.4–4.50), controllability and state scaling."""
