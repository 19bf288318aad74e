// The P/Invoke declarations of libvcinpl2.so (the VCI C API v2 and canemu's extensions) that the
// assembly is built on. Structures cross as byte arrays laid out as cantype.h / lintype.h /
// vcitype.h pack them (pack 1), read and written by the helpers of Bytes: no marshalling layout
// to get wrong, and the sizes are asserted where the buffers are made.
using System;
using System.Runtime.InteropServices;
using System.Text;

namespace Ixxat.Vci3
{
  internal static class Native
  {
    const string Lib = "libvcinpl2.so";

    public const uint VCI_OK = 0;
    public static uint Code(uint n) { return 0xE0010000u | n; }
    public static readonly uint E_UNEXPECTED = Code(0x01);
    public static readonly uint E_NOTIMPL = Code(0x02);
    public static readonly uint E_INVALIDARG = Code(0x04);
    public static readonly uint E_INVHANDLE = Code(0x06);
    public static readonly uint E_ACCESSDENIED = Code(0x0A);
    public static readonly uint E_TIMEOUT = Code(0x0B);
    public static readonly uint E_NO_MORE_ITEMS = Code(0x0F);
    public static readonly uint E_RXQUEUE_EMPTY = Code(0x12);
    public static readonly uint E_TXQUEUE_FULL = Code(0x13);
    public static readonly uint E_INVALID_STATE = Code(0x15);

    // Sizes of the structures (bytes).
    public const int DeviceInfoSize = 304, DeviceCapsSize = 66, CanMsg2Size = 80;
    public const int CanCaps2Size = 108, CanLineStatus2Size = 40, CanChanStatus2Size = 44;
    public const int CanCyclic2Size = 76, CanSchedStatus2Size = 57, BtpSize = 16;
    public const int LinMsgSize = 16, LinCapsSize = 12, LinLineStatusSize = 8;

    [DllImport(Lib)] public static extern uint vciInitialize();
    [DllImport(Lib)] public static extern void vciFormatErrorA(uint hr, StringBuilder text, uint len);
    [DllImport(Lib)] public static extern uint vciEnumDeviceOpen(out IntPtr h);
    [DllImport(Lib)] public static extern uint vciEnumDeviceClose(IntPtr h);
    [DllImport(Lib)] public static extern uint vciEnumDeviceNext(IntPtr h, byte[] info);
    [DllImport(Lib)] public static extern uint vciEnumDeviceReset(IntPtr h);
    [DllImport(Lib)] public static extern uint vciEnumDeviceWaitEvent(IntPtr h, uint ms);
    [DllImport(Lib)] public static extern uint vciDeviceOpen(ref long vciid, out IntPtr h);
    [DllImport(Lib)] public static extern uint vciDeviceClose(IntPtr h);
    [DllImport(Lib)] public static extern uint vciDeviceGetInfo(IntPtr h, byte[] info);
    [DllImport(Lib)] public static extern uint vciDeviceGetCaps(IntPtr h, byte[] caps);

    [DllImport(Lib)] public static extern uint canControlOpen(IntPtr dev, uint no, out IntPtr h);
    [DllImport(Lib)] public static extern uint canControlClose(IntPtr h);
    [DllImport(Lib)] public static extern uint canControlGetCaps(IntPtr h, byte[] caps);
    [DllImport(Lib)] public static extern uint canControlGetStatus(IntPtr h, byte[] status);
    [DllImport(Lib)]
    public static extern uint canControlDetectBitrate(IntPtr h, byte opMode, byte exMode,
        ushort timeout, uint count, byte[] sdr, byte[] fdr, out uint index);
    [DllImport(Lib)]
    public static extern uint canControlInitialize(IntPtr h, byte opMode, byte exMode, byte sfMode,
        byte efMode, uint sfIds, uint efIds, byte[] sdr, byte[] fdr);
    [DllImport(Lib)] public static extern uint canControlReset(IntPtr h);
    [DllImport(Lib)] public static extern uint canControlStart(IntPtr h, int start);
    [DllImport(Lib)] public static extern uint canControlSetAccFilter(IntPtr h, int ext, uint code, uint mask);
    [DllImport(Lib)] public static extern uint canControlAddFilterIds(IntPtr h, int ext, uint code, uint mask);
    [DllImport(Lib)] public static extern uint canControlRemFilterIds(IntPtr h, int ext, uint code, uint mask);

    [DllImport(Lib)] public static extern uint canChannelOpen(IntPtr dev, uint no, int excl, out IntPtr h);
    [DllImport(Lib)] public static extern uint canChannelClose(IntPtr h);
    [DllImport(Lib)] public static extern uint canChannelGetCaps(IntPtr h, byte[] caps);
    [DllImport(Lib)] public static extern uint canChannelGetStatus(IntPtr h, byte[] status);
    [DllImport(Lib)]
    public static extern uint canChannelInitialize(IntPtr h, ushort rx, ushort rxThreshold, ushort tx,
        ushort txThreshold, uint filterSize, byte filterMode);
    [DllImport(Lib)] public static extern uint canChannelActivate(IntPtr h, int enable);
    [DllImport(Lib)] public static extern uint canChannelPeekMessage(IntPtr h, byte[] msg);
    [DllImport(Lib)] public static extern uint canChannelPostMessage(IntPtr h, byte[] msg);
    [DllImport(Lib)] public static extern uint canChannelWaitRxEvent(IntPtr h, uint ms);
    [DllImport(Lib)] public static extern uint canChannelWaitTxEvent(IntPtr h, uint ms);

    [DllImport(Lib)] public static extern uint canSchedulerOpen(IntPtr dev, uint no, out IntPtr h);
    [DllImport(Lib)] public static extern uint canSchedulerClose(IntPtr h);
    [DllImport(Lib)] public static extern uint canSchedulerGetCaps(IntPtr h, byte[] caps);
    [DllImport(Lib)] public static extern uint canSchedulerGetStatus(IntPtr h, byte[] status);
    [DllImport(Lib)] public static extern uint canSchedulerActivate(IntPtr h, int enable);
    [DllImport(Lib)] public static extern uint canSchedulerReset(IntPtr h);
    [DllImport(Lib)] public static extern uint canSchedulerAddMessage(IntPtr h, byte[] msg, out uint index);
    [DllImport(Lib)] public static extern uint canSchedulerRemMessage(IntPtr h, uint index);
    [DllImport(Lib)] public static extern uint canSchedulerStartMessage(IntPtr h, uint index, ushort repeat);
    [DllImport(Lib)] public static extern uint canSchedulerStopMessage(IntPtr h, uint index);

    [DllImport(Lib)] public static extern uint linControlOpen(IntPtr dev, uint no, out IntPtr h);
    [DllImport(Lib)] public static extern uint linControlClose(IntPtr h);
    [DllImport(Lib)] public static extern uint linControlGetCaps(IntPtr h, byte[] caps);
    [DllImport(Lib)] public static extern uint linControlGetStatus(IntPtr h, byte[] status);
    [DllImport(Lib)] public static extern uint linControlInitialize(IntPtr h, byte mode, ushort bitrate);
    [DllImport(Lib)] public static extern uint linControlReset(IntPtr h);
    [DllImport(Lib)] public static extern uint linControlStart(IntPtr h, int start);
    [DllImport(Lib)] public static extern uint linControlWriteMessage(IntPtr h, int send, byte[] msg);
    [DllImport(Lib)] public static extern uint linMonitorOpen(IntPtr dev, uint no, int excl, out IntPtr h);
    [DllImport(Lib)] public static extern uint linMonitorClose(IntPtr h);
    [DllImport(Lib)] public static extern uint linMonitorGetCaps(IntPtr h, byte[] caps);
    [DllImport(Lib)] public static extern uint linMonitorGetStatus(IntPtr h, byte[] status);
    [DllImport(Lib)] public static extern uint linMonitorInitialize(IntPtr h, ushort size, ushort threshold);
    [DllImport(Lib)] public static extern uint linMonitorActivate(IntPtr h, int enable);
    [DllImport(Lib)] public static extern uint linMonitorPeekMessage(IntPtr h, byte[] msg);
    [DllImport(Lib)] public static extern uint linMonitorWaitRxEvent(IntPtr h, uint ms);

    [DllImport(Lib)] public static extern uint canemuConnect(string socket);
    [DllImport(Lib)] public static extern uint canemuStepTime(ulong ns, out ulong now);
    [DllImport(Lib)] public static extern uint canemuGetTime(out ulong now, out byte mode);
    [DllImport(Lib)]
    public static extern uint canemuGetControllerState(IntPtr h, out byte errorState, out ushort tec,
        out ushort rec, out byte lineState);
    [DllImport(Lib)]
    public static extern uint canemuCreateDevice(string bus, string name, out long vciid,
        StringBuilder nameOut, uint cbNameOut);
    [DllImport(Lib)] public static extern uint canemuRemoveDevice(string name);

    // The library's text for hr (its detail of the last failure included).
    public static string Text(uint hr)
    {
      var sb = new StringBuilder(512);
      try { vciFormatErrorA(hr, sb, 512); } catch (Exception) { return ""; }
      return sb.ToString();
    }

    // VciException unless hr is VCI_OK: "what: the library's text".
    public static void Check(uint hr, string what)
    {
      if (hr != VCI_OK) throw new VciException(hr, what + ": " + Text(hr));
    }
  }

  // Little-endian reads and writes in the structure buffers.
  internal static class Bytes
  {
    public static ushort U16(byte[] b, int at) { return (ushort)(b[at] | b[at + 1] << 8); }
    public static uint U32(byte[] b, int at) { return BitConverter.ToUInt32(b, at); }
    public static void Put16(byte[] b, int at, ushort v) { b[at] = (byte)v; b[at + 1] = (byte)(v >> 8); }
    public static void Put32(byte[] b, int at, uint v) { Buffer.BlockCopy(BitConverter.GetBytes(v), 0, b, at, 4); }
    public static string Latin1(byte[] b, int at, int max)
    {
      int end = at;
      while (end < at + max && b[end] != 0) end++;
      return Encoding.GetEncoding(28591).GetString(b, at, end - at);
    }
  }
}
