//! Where the Foxglove WebSocket server listens: loopback unless an address is named.
//!
//! `--foxglove` takes `PORT`, `:PORT`, `HOST:PORT` or `[IPv6]:PORT`. Without a host (the
//! first two forms) the server binds 127.0.0.1, never every interface (as `:PORT` means for
//! many servers): the protocol has no authentication, so reaching it from another machine is
//! a choice the user makes by naming that address (`0.0.0.0:8765`, a LAN address). The host
//! must be an IP literal or `localhost`: a host name that resolves elsewhere is refused.

use std::net::{IpAddr, Ipv4Addr, SocketAddr};

/// The default address: loopback, Foxglove's usual port.
pub const DEFAULT_FOXGLOVE: &str = "127.0.0.1:8765";

/// A parsed `--foxglove` address.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FoxgloveAddr {
    /// Where to bind.
    pub addr: SocketAddr,
    /// The user named a non-loopback address (the server is then reachable from the network).
    pub remote: bool,
}

/// A `--foxglove` value that is not an address.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "--foxglove {given:?}: expected PORT, :PORT, HOST:PORT or [IPv6]:PORT with HOST an IP \
     address or localhost (default {DEFAULT_FOXGLOVE}; a non-loopback address binds beyond this \
     machine only when named)"
)]
pub struct AddrError {
    /// The value given.
    pub given: String,
}

impl FoxgloveAddr {
    /// Parses `s` (see the module docs).
    pub fn parse(s: &str) -> Result<FoxgloveAddr, AddrError> {
        let err = || AddrError {
            given: s.to_owned(),
        };
        let s = s.trim();
        let port = |p: &str| p.parse::<u16>().map_err(|_| err());
        let loopback = IpAddr::V4(Ipv4Addr::LOCALHOST);
        let (ip, port) = if let Some(p) = s.strip_prefix(':') {
            (loopback, port(p)?)
        } else if !s.contains(':')
            && !s.contains('.')
            && !s.is_empty()
            && s.chars().all(|c| c.is_ascii_digit())
        {
            (loopback, port(s)?)
        } else if let Ok(a) = s.parse::<SocketAddr>() {
            (a.ip(), a.port())
        } else {
            let (host, p) = s.rsplit_once(':').ok_or_else(err)?;
            if host.eq_ignore_ascii_case("localhost") {
                (loopback, port(p)?)
            } else {
                return Err(err());
            }
        };
        Ok(FoxgloveAddr {
            addr: SocketAddr::new(ip, port),
            remote: !ip.is_loopback(),
        })
    }

    /// The WebSocket URL a Foxglove client connects to.
    pub fn url(&self) -> String {
        format!("ws://{}", self.addr)
    }
}

impl Default for FoxgloveAddr {
    fn default() -> FoxgloveAddr {
        FoxgloveAddr::parse(DEFAULT_FOXGLOVE).expect("the default parses")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn loopback_unless_an_address_is_named() {
        for s in [
            "8765",
            ":8765",
            "localhost:8765",
            "127.0.0.1:8765",
            DEFAULT_FOXGLOVE,
        ] {
            let a = FoxgloveAddr::parse(s).unwrap();
            assert!(a.addr.ip().is_loopback() && !a.remote, "{s}");
            assert_eq!(a.addr.port(), 8765);
        }
        let v6 = FoxgloveAddr::parse("[::1]:9000").unwrap();
        assert!(v6.addr.ip().is_loopback() && !v6.remote);
        for named in ["0.0.0.0:8765", "192.168.1.20:8765", "[::]:8765"] {
            assert!(FoxgloveAddr::parse(named).unwrap().remote, "{named}");
        }
        for bad in [
            "",
            "robot.local:8765",
            "0.0.0.0",
            "host",
            ":99999",
            "8765x",
            "1.2.3.4:",
        ] {
            let e = FoxgloveAddr::parse(bad).unwrap_err().to_string();
            assert!(e.contains("--foxglove") && !e.contains('\n'), "{bad}: {e}");
        }
    }
}
