"""The DIS link kind: the own ship as Entity State PDUs, other simulators' entities heard."""
