/*
 * net.h - TCP sockets for the farm: listening, non-blocking connects, address
 * parsing. Everything returns an error text instead of printing.
 */
#ifndef PORTRAY_NET_H
#define PORTRAY_NET_H

#include <stdbool.h>
#include <stddef.h>

#define NET_HOST_LEN 256
#define NET_PORT_LEN 16

/* Splits "HOST:PORT" or "[V6]:PORT" (PORT required, 0..65535). 0 or -1 with err. */
int net_parse_hostport(const char *s, char host[NET_HOST_LEN], char port[NET_PORT_LEN], char *err,
		       size_t errlen);
/* A non-blocking listening socket on host:port (port "0": any). fd, or -1 with err. */
int net_listen(const char *host, const char *port, char *err, size_t errlen);
/* The local port a socket is bound to, or -1. */
int net_local_port(int fd);
/* Accepts one connection as a non-blocking socket with TCP_NODELAY; fd, or -1 (errno set). */
int net_accept(int lfd, char *peer, size_t peerlen);
/*
 * Starts a non-blocking connect to host:port (numeric or resolvable). Returns
 * the fd (connect in progress or done), or -1 with err.
 */
int net_connect_start(const char *host, const char *port, char *err, size_t errlen);
/* After the fd became writable: 0 if connected, or -1 with err. */
int net_connect_finish(int fd, char *err, size_t errlen);
/*
 * Writes value and a newline to path through a temporary file renamed over
 * it, so a reader (a test waiting for --port-file) never sees half of it.
 * 0, or -1 (errno).
 */
int net_write_number(const char *path, long value);
/* Whether host (numeric or a name) names only loopback addresses
 * (127.0.0.0/8, ::1, "localhost"); false when it cannot be resolved. */
bool net_is_loopback(const char *host);
/* Monotonic clock in seconds. */
double net_now(void);

#endif
