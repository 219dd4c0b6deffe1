"""Captures (pcap/pcapng) of RTDE and primary/secondary traffic, decoded into tables."""
