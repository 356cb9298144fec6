"""The MuJoCo machines, built with MjSpec from numeric layouts and physical parameters (each with its unit and
source); they know no job and no cutting."""
