//! The addresses this machine is reached at: what a studio listening on
//! every interface (`--listen 0.0.0.0` or `::`) must admit as its `Host`
//! and print for the user to open.

use std::net::IpAddr;

/// The addresses of this machine's network interfaces, loopback included,
/// in the order the system lists them; none where it cannot say.
#[cfg(unix)]
pub fn addresses() -> Vec<IpAddr> {
    let mut found = Vec::new();
    let mut list: *mut libc::ifaddrs = std::ptr::null_mut();
    // getifaddrs fills a linked list that freeifaddrs releases; every
    // pointer read below belongs to that list and is read before it is
    // freed.
    #[allow(unsafe_code)]
    unsafe {
        if libc::getifaddrs(&mut list) != 0 {
            return found;
        }
        let mut entry = list;
        while let Some(interface) = entry.as_ref() {
            if let Some(address) = interface.ifa_addr.as_ref() {
                match i32::from(address.sa_family) {
                    libc::AF_INET => {
                        let v4 = &*interface.ifa_addr.cast::<libc::sockaddr_in>();
                        // Stored in network order: its bytes in memory are the address's.
                        found.push(IpAddr::from(v4.sin_addr.s_addr.to_ne_bytes()));
                    }
                    libc::AF_INET6 => {
                        let v6 = &*interface.ifa_addr.cast::<libc::sockaddr_in6>();
                        found.push(IpAddr::from(v6.sin6_addr.s6_addr));
                    }
                    _ => {}
                }
            }
            entry = interface.ifa_next;
        }
        libc::freeifaddrs(list);
    }
    found.dedup();
    found
}

/// Elsewhere the interfaces are not listed: only the loopback names and
/// the listen address are admitted.
#[cfg(not(unix))]
pub fn addresses() -> Vec<IpAddr> {
    Vec::new()
}

/// This machine's host name, if the system gives one.
#[cfg(unix)]
pub fn host_name() -> Option<String> {
    let mut buffer = [0u8; 256];
    #[allow(unsafe_code)]
    // gethostname writes at most the buffer's length, NUL-terminated when
    // it fits.
    let done = unsafe { libc::gethostname(buffer.as_mut_ptr().cast(), buffer.len()) };
    if done != 0 {
        return None;
    }
    let end = buffer.iter().position(|&b| b == 0)?;
    let name = std::str::from_utf8(&buffer[..end]).ok()?;
    (!name.is_empty()).then(|| name.to_string())
}

/// Elsewhere no host name is admitted beyond the loopback names.
#[cfg(not(unix))]
pub fn host_name() -> Option<String> {
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_loopback_interface_is_listed() {
        assert!(
            addresses().iter().any(IpAddr::is_loopback),
            "{:?}",
            addresses()
        );
    }
}
