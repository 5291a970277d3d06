"""Two-jaw grasps: contact graph, release energy and jaw-pair quantities (SPEC §4)."""
