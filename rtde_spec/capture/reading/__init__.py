"""Reading: frames out of pcap/pcapng files (records, resync, link and IP headers, fragments, bulk runs)."""
