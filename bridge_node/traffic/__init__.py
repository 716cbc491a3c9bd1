"""The traffic picture: the other vessels of the exercise, from DIS, from replayed AIS logs
and scripted in the config, gathered for the AIS outputs and the state stream."""
