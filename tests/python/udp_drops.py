"""Counting messages that loopback UDP itself lost (tests/net/lcm/udp_drops.h for C).

udpm over loopback is still UDP: when a receiving thread is descheduled (2 cores, other tests
beside it) its socket buffer fills and the kernel drops datagrams, and counts each drop: a
socket's full buffer in /proc/net/snmp (Udp RcvbufErrors), the loopback device's full backlog in
/proc/net/softnet_stat (second column). A test counting arrivals accepts a shortfall only up to
the drops the kernel counted meanwhile; a message missing that the kernel did not drop fails.
The counters are the network namespace's, so other tests' drops may count too: one-sided."""

# receive buffers of the tests' sockets: large, so that drops are rare (capped at rmem_max)
URL_OPTIONS = "ttl=0&recv_buf_size=4194304"


def udp_drops_now():
    """Every datagram this network namespace's kernel has dropped on receipt so far."""
    with open("/proc/net/snmp") as f:
        lines = f.read().splitlines()
    rcvbuf = 0
    for head, vals in zip(lines, lines[1:]):
        if head.startswith("Udp:") and vals.startswith("Udp:"):
            rcvbuf = int(vals.split()[head.split().index("RcvbufErrors")])
            break
    with open("/proc/net/softnet_stat") as f:
        backlog = sum(int(line.split()[1], 16) for line in f if line.strip())
    return rcvbuf + backlog
