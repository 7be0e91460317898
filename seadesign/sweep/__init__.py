"""How candidates are run and chosen: the per-candidate stages, the sweep, ranking and the
spring.json writer."""
