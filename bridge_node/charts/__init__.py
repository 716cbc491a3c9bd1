"""Ice charts: SIGRID-3 shapefiles read into the field's ice regions."""
