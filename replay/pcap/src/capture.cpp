// SPDX-License-Identifier: Apache-2.0
#include "sim/pcap/capture.hpp"

#include <pcap/pcap.h>
#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <limits>
#include <utility>

#include "ip_reassembly.hpp"

namespace sim::pcap {

struct CaptureReader::Impl {
  pcap_t* handle = nullptr;
  std::string name;
  LinkType link;
  CaptureOptions options;
  CaptureStats stats;
  std::int64_t file_size = -1;
  Error error{ErrorCode::system_error, ""};
  Ipv4Reassembler reassembler;

  void update_fragment_stats() noexcept {
    const ReassemblyCounters& c = reassembler.counters();
    stats.reassembled = c.completed;
    stats.fragments_reassembled = c.fragments_used;
    stats.fragments_incomplete = c.incomplete();
    stats.fragments_refused = c.refused;
  }

  ~Impl() {
    if (handle != nullptr) pcap_close(handle);  // also closes the FILE* it was opened from
  }
};

namespace {

Error invalid(std::string message) { return Error{ErrorCode::invalid_argument, std::move(message)}; }

// Shared by both open() overloads once libpcap has accepted the file's header.
Expected<std::unique_ptr<CaptureReader::Impl>> configure(std::unique_ptr<CaptureReader::Impl> impl) {
  struct stat info {};
  std::FILE* file = pcap_file(impl->handle);
  if (file != nullptr && fileno(file) >= 0 && fstat(fileno(file), &info) == 0 &&
      S_ISREG(info.st_mode)) {
    impl->file_size = info.st_size;
  }
  impl->link = LinkType{pcap_datalink(impl->handle)};
  if (!is_supported(impl->link)) {
    return invalid(impl->name + " has link type " + describe(impl->link) +
                   ", which the capture reader cannot parse (it reads " + supported_link_types() +
                   "); capture on the sensor's Ethernet interface, or convert the file with "
                   "editcap -T.");
  }
  const std::string expression = bpf_expression(impl->options, impl->link);
  if (!expression.empty()) {
    bpf_program program{};
    if (pcap_compile(impl->handle, &program, expression.c_str(), 1, PCAP_NETMASK_UNKNOWN) != 0) {
      return invalid("the packet filter \"" + expression + "\" does not compile (" +
                     pcap_geterr(impl->handle) + "); fix the --filter expression.");
    }
    const int rc = pcap_setfilter(impl->handle, &program);
    pcap_freecode(&program);
    if (rc != 0) {
      return Error{ErrorCode::system_error, "cannot apply the packet filter to " + impl->name +
                                                ": " + pcap_geterr(impl->handle) + "."};
    }
  }
  return impl;
}

Error open_failure(const std::string& name, const char* pcap_message) {
  return invalid(name + " is not a capture file libpcap can read (" + pcap_message +
                 "); give a .pcap or .pcapng file, e.g. recorded with tcpdump -w.");
}

}  // namespace

std::string bpf_expression(const CaptureOptions& options, LinkType link) {
  std::string port_expression;
  if (options.port) {
    // BPF's "udp" does not look behind IPv6 extension headers, so IPv6 passes this pre-filter
    // and next() checks its port after parsing.
    // Later IPv4 fragments carry no UDP header: they pass too, and next() checks the port of
    // the datagram they rebuild.
    const std::string udp = "udp port " + std::to_string(*options.port) +
                            " or ip6 or (udp and ip[6:2] & 0x1fff != 0)";
    // Each "vlan" moves libpcap's offsets by one tag for the rest of the expression, so the
    // tagged alternatives nest instead of repeating "vlan and vlan".
    port_expression = link.dlt == DLT_EN10MB
                          ? "(" + udp + " or (vlan and (" + udp + " or (vlan and (" + udp + ")))))"
                          : "(" + udp + ")";
  }
  if (options.filter.empty()) return port_expression;
  // The user's expression goes first: after the port expression's "vlan" it would be read at
  // the offsets of a tagged frame.
  if (port_expression.empty()) return "(" + options.filter + ")";
  return "(" + options.filter + ") and " + port_expression;
}

Expected<CaptureReader> CaptureReader::open(const std::string& path, const CaptureOptions& options) {
  struct stat info {};
  if (::stat(path.c_str(), &info) != 0) {
    return Error{errno == ENOENT ? ErrorCode::not_found : ErrorCode::system_error,
                 "cannot open capture " + path + ": " + std::strerror(errno) + "."};
  }
  if (S_ISDIR(info.st_mode)) return invalid(path + " is a directory; give a .pcap or .pcapng file.");
  char message[PCAP_ERRBUF_SIZE] = {};
  pcap_t* handle =
      pcap_open_offline_with_tstamp_precision(path.c_str(), PCAP_TSTAMP_PRECISION_NANO, message);
  if (handle == nullptr) return open_failure(path, message);
  auto impl = std::make_unique<Impl>();
  impl->handle = handle;
  impl->name = path;
  impl->options = options;
  auto configured = configure(std::move(impl));
  if (!configured) return configured.error();
  return CaptureReader(std::move(configured.value()));
}

Expected<CaptureReader> CaptureReader::open(std::FILE* stream, const std::string& name,
                                            const CaptureOptions& options) {
  if (stream == nullptr) return invalid("no stream to read the capture " + name + " from.");
  char message[PCAP_ERRBUF_SIZE] = {};
  pcap_t* handle =
      pcap_fopen_offline_with_tstamp_precision(stream, PCAP_TSTAMP_PRECISION_NANO, message);
  if (handle == nullptr) {
    std::fclose(stream);  // libpcap leaves the stream open when it refuses it
    return open_failure(name, message);
  }
  auto impl = std::make_unique<Impl>();
  impl->handle = handle;
  impl->name = name;
  impl->options = options;
  auto configured = configure(std::move(impl));
  if (!configured) return configured.error();
  return CaptureReader(std::move(configured.value()));
}

CaptureReader::CaptureReader(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
CaptureReader::CaptureReader(CaptureReader&&) noexcept = default;
CaptureReader& CaptureReader::operator=(CaptureReader&&) noexcept = default;
CaptureReader::~CaptureReader() = default;

namespace {
// The record's capture time for fragment timeouts (0 when the stamp cannot be one).
std::int64_t record_ns(const pcap_pkthdr& header) noexcept {
  if (header.ts.tv_sec < 0 || header.ts.tv_sec > 9'000'000'000 || header.ts.tv_usec < 0) return 0;
  return std::int64_t{header.ts.tv_sec} * 1'000'000'000 + header.ts.tv_usec;
}
}  // namespace

NextStatus CaptureReader::next(Datagram& out) noexcept {
  Impl& s = *impl_;
  for (;;) {
    pcap_pkthdr* header = nullptr;
    const u_char* data = nullptr;
    const int rc = pcap_next_ex(s.handle, &header, &data);
    if (rc == PCAP_ERROR_BREAK) {
      s.reassembler.finish();  // what is still pending will never complete
      s.update_fragment_stats();
      return NextStatus::end;
    }
    if (rc != 1) {
      // Offline reads fail only on a damaged file: libpcap says "truncated dump file; …".
      s.error = Error{ErrorCode::invalid_argument,
                      s.name + " is damaged after record " + std::to_string(s.stats.records) +
                          " (" + pcap_geterr(s.handle) +
                          "); the capture was cut short: use the records before it or record again."};
      return NextStatus::error;
    }
    ++s.stats.records;
    const std::span<const std::byte> frame(reinterpret_cast<const std::byte*>(data), header->caplen);
    Ipv4Fragment fragment;
    switch (parse_frame(s.link, frame, out, &fragment)) {
      case FrameStatus::ok: break;
      case FrameStatus::not_ip: ++s.stats.not_ip; continue;
      case FrameStatus::not_udp: ++s.stats.not_udp; continue;
      case FrameStatus::fragment: {
        ++s.stats.fragments;
        const auto whole = s.reassembler.add(fragment, record_ns(*header));
        s.update_fragment_stats();
        if (whole.empty()) continue;
        const FrameStatus status = parse_reassembled(fragment, whole, out);
        if (status == FrameStatus::truncated) ++s.stats.truncated;
        if (status == FrameStatus::malformed) ++s.stats.malformed;
        if (status != FrameStatus::ok) continue;
        break;
      }
      case FrameStatus::truncated: ++s.stats.truncated; continue;
      case FrameStatus::malformed:
      case FrameStatus::unsupported_link: ++s.stats.malformed; continue;
    }
    if (s.options.port && out.source.port != *s.options.port &&
        out.destination.port != *s.options.port) {
      ++s.stats.other_port;
      continue;
    }
    // Opened with nanosecond precision, libpcap scales µs files: tv_usec holds nanoseconds.
    // pcapng stamps are 64-bit: one past the year 2262 does not fit in int64 nanoseconds.
    constexpr std::int64_t latest_second = std::numeric_limits<std::int64_t>::max() / 1'000'000'000 - 1;
    if (header->ts.tv_sec < 0 || header->ts.tv_sec > latest_second || header->ts.tv_usec < 0 ||
        header->ts.tv_usec >= 1'000'000'000) {
      ++s.stats.malformed;
      continue;
    }
    out.timestamp_ns = std::int64_t{header->ts.tv_sec} * 1'000'000'000 + header->ts.tv_usec;
    ++s.stats.datagrams;
    return NextStatus::datagram;
  }
}

double CaptureReader::progress() const noexcept {
  std::FILE* file = pcap_file(impl_->handle);
  if (impl_->file_size <= 0 || file == nullptr) return -1.0;
  const long position = std::ftell(file);
  if (position < 0) return -1.0;
  return static_cast<double>(position) / static_cast<double>(impl_->file_size);
}

const Error& CaptureReader::error() const noexcept { return impl_->error; }
LinkType CaptureReader::link_type() const noexcept { return impl_->link; }
const CaptureStats& CaptureReader::stats() const noexcept { return impl_->stats; }
const std::string& CaptureReader::name() const noexcept { return impl_->name; }

}  // namespace sim::pcap
